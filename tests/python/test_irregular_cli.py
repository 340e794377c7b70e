"""brdfz info / diff on scattered measurements: Cornell .brdf and ALTA .dat files."""
import json
import math

import pytest

from conftest import SHARED, run

WAVELENGTHS = list(range(400, 701, 10))
INFO_KEYS = {"format", "dims", "valid", "negative", "nan", "inf", "nbytes", "albedo"}


def write_cornell(path, records):
    """records: (theta_i, phi_i, theta_o, phi_o, spectrum of 31 values)."""
    with open(path, "w") as f:
        f.write("# synthetic\n31\n" + " ".join(map(str, WAVELENGTHS)) + "\n")
        for *angles, spectrum in records:
            f.write(" ".join(repr(v) for v in [*angles, *spectrum]) + "\n")


def proj_directions(theta_l, x, y):
    """wi, wo of an ALTA ISOTROPIC_TL_TV_PROJ_DPHI row."""
    tv = math.hypot(x, y)
    s = math.sin(tv) / tv if tv > 0 else 0.0
    return [math.sin(theta_l), 0.0, math.cos(theta_l)], [s * x, s * y, math.cos(tv)]


def proj_grid():
    rows = []
    for theta_l in (0.2, 0.6, 1.0):
        for i in range(-6, 7):
            for j in range(-6, 7):
                x, y = 0.22 * i, 0.22 * j
                if math.hypot(x, y) < 1.5:
                    rows.append((theta_l, x, y))
    return rows


def write_alta(path, rows, values):
    with open(path, "w") as f:
        f.write("#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n")
        for (tl, x, y), v in zip(rows, values):
            f.write(f"{tl!r} {x!r} {y!r} {v!r}\n")


def info_json(cli, path):
    return json.loads(run(cli, "info", path, "--json").stdout)


def test_info_on_synthetic_cornell_and_alta(cli, tmp_path):
    cornell = tmp_path / "flat.brdf"
    write_cornell(cornell, [(0.3, 0.0, 0.3, math.pi, [0.5] * 31), (0.5, 0.0, 0.2, 3.0, [2.0] * 31)])
    info = info_json(cli, cornell)
    assert INFO_KEYS <= set(info)
    assert info["format"] == "cornell"
    assert info["dims"] == [2, 31]
    assert (info["valid"], info["negative"], info["nan"], info["inf"]) == (2, 0, 0, 0)
    assert info["albedo"] == []  # not defined for scattered samples
    assert info["nbytes"] == 2 * 9 * 8  # wi, wo, f: nine float64 per sample
    assert info["min"] == pytest.approx(0.5) and info["max"] == pytest.approx(2.0)  # flat spectra: grey
    text = run(cli, "info", cornell).stdout
    assert "not defined for scattered samples" in text

    alta = tmp_path / "tape.dat"
    write_alta(alta, [(0.2, 0.1, 0.0), (0.2, -1.6, 0.0), (0.2, 0.3, 0.1)], [1.0, 2.0, float("nan")])
    info = info_json(cli, alta)
    assert info["format"] == "alta"
    assert info["dims"] == [3, 1]
    assert (info["valid"], info["nan"], info["below_horizon"]) == (1, 1, 1)
    assert info["channels"] == 1


def test_diff_judges_a_table_at_measured_points(cli, demo_table, tmp_path):
    # ALTA values = the demo table's green channel at each row's directions: green agrees to rounding,
    # red and blue do not.
    rows = proj_grid()
    pairs = tmp_path / "pairs.csv"
    with open(pairs, "w") as f:
        for row in rows:
            wi, wo = proj_directions(*row)
            f.write(",".join(repr(c) for c in wi + wo) + "\n")
    rgb = [[float(c) for c in line.split(",")] for line in run(cli, "eval", demo_table, "--pairs", pairs).stdout.split()]
    alta = tmp_path / "green.dat"
    write_alta(alta, rows, [c[1] for c in rgb])

    m = json.loads(run(cli, "diff", alta, demo_table, "--json").stdout)
    inside = sum(1 for row in rows if all(w[2] > math.cos(math.radians(80)) for w in proj_directions(*row)))
    assert m["samples"] == inside
    assert m["cos_rmse"]["g"] < 1e-9
    assert m["cos_rmse"]["r"] > 1e-3 and m["cos_rmse"]["b"] > 1e-3
    text = run(cli, "diff", alta, demo_table).stdout
    assert "cos_rmse" in text


def test_measurements_are_not_brdfs(cli, demo_table, tmp_path):
    cornell = tmp_path / "a.brdf"
    write_cornell(cornell, [(0.3, 0.0, 0.3, math.pi, [0.5] * 31)])
    for args in (("diff", demo_table, cornell), ("eval", cornell, "--wi", "0,0,1", "--wo", "0,0,1")):
        proc = run(cli, *args, check=False)
        assert proc.returncode != 0
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and "scattered measurements" in lines[0], proc.stderr


@pytest.mark.parametrize(
    "name, text, expect",
    [
        ("count.brdf", "# c\nthirty-one\n", ": line 2: expected the number of wavelengths"),
        ("record.brdf", "31\n" + " ".join(map(str, WAVELENGTHS)) + "\n0.1 0 0.1 3 0.5\n", ": line 3: a record needs 35"),
        ("dim.dat", "#DIM 3\n", ": line 1: #DIM needs two integers"),
        ("row.dat", "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n0.1 0.2 x 1\n", ": line 3: expected a number"),
        ("param.dat", "#DIM 2 1\n#PARAM_IN STARK_2D\n0.1 0.2 1\n", "'STARK_2D' is not supported"),
    ],
)
def test_bad_files_fail_with_one_line_naming_file_and_line(cli, tmp_path, name, text, expect):
    path = tmp_path / name
    path.write_text(text)
    for args in (("info", path), ("diff", path, path.with_suffix(".binary"))):
        proc = run(cli, *args, check=False)
        assert proc.returncode != 0
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and str(path) in lines[0] and expect in lines[0], proc.stderr


def test_real_cornell_and_alta_files(cli, demo_table):
    cornell = sorted((SHARED / "data" / "cornell").glob("*.brdf"))
    alta = sorted((SHARED / "data" / "alta").glob("*.dat"))
    if not cornell or not alta:
        pytest.skip("../shared/data/cornell or alta is missing")
    for path in cornell:
        info = info_json(cli, path)
        assert info["dims"] == [1439, 31]
        assert info["valid"] + info["negative"] == 1439
        assert info["max"] > 10  # glossy car paints
    info = info_json(cli, alta[0])
    assert info["dims"] == [7405, 1]
    assert info["below_horizon"] == 86
    assert info["samples"] == 7405 - 86

    m = json.loads(run(cli, "diff", cornell[0], demo_table, "--json").stdout)
    assert m["samples"] > 1000
    assert all(math.isfinite(m[k]["mean"]) for k in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"))
