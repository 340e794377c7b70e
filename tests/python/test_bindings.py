"""The Python package against the brdfz command: numpy results equal the CLI's for the same inputs
(float32 and float64), shapes and dtypes are checked, library errors arrive with their messages,
files round-trip through save / load / convert, and long operations report progress."""
import json
import threading
import time

import numpy as np
import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()


def random_dirs(rng, n, upper=True):
    v = rng.normal(size=(n, 3))
    if upper:
        v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def cli_eval(cli, path, wi, wo, tmp_path):
    pairs = tmp_path / "pairs.csv"
    np.savetxt(pairs, np.hstack([wi, wo]).astype(np.float64), delimiter=",", fmt="%.17g")
    out = run(cli, "eval", path, "--pairs", pairs).stdout
    return np.array([[float(x) for x in line.split(",")] for line in out.splitlines() if line.strip()])


def cli_error(cli, *args):
    """The message the CLI prints for a failing command (without its "brdfz: " prefix)."""
    proc = run(cli, *args, check=False)
    assert proc.returncode != 0
    line = proc.stderr.strip().splitlines()[-1]
    assert line.startswith("brdfz: ")
    return line[len("brdfz: "):]


@pytest.fixture(scope="module")
def demo(demo_table):
    return brdfz.load(demo_table)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_eval_equals_cli(cli, demo_table, demo, tmp_path, dtype):
    rng = np.random.default_rng(1)
    # Non-unit rows and some below the horizon: both sides normalise and return 0 there alike.
    wi = (random_dirs(rng, 2000, upper=False) * rng.uniform(0.5, 2.0, (2000, 1))).astype(dtype)
    wo = random_dirs(rng, 2000).astype(dtype)
    f = demo.eval(wi, wo)
    assert f.dtype == np.float64 and f.shape == (2000, 3)
    assert np.array_equal(f, cli_eval(cli, demo_table, wi, wo, tmp_path))
    assert (f[wi[:, 2] <= 0] == 0).all() and (f[wi[:, 2] > 0] > 0).any()


def test_eval_equals_cli_on_real_files(cli, rgl_files, merl_tables, tmp_path):
    rng = np.random.default_rng(2)
    wi, wo = random_dirs(rng, 500), random_dirs(rng, 500)
    for path in [rgl_files[0], merl_tables[0]]:
        assert np.array_equal(brdfz.load(path).eval(wi, wo), cli_eval(cli, path, wi, wo, tmp_path)), path


def test_eval_cos_pdf_sample_agree(cli, demo_table, demo):
    rng = np.random.default_rng(3)
    wi, wo = random_dirs(rng, 1000), random_dirs(rng, 1000)
    assert np.allclose(demo.eval_cos(wi, wo), demo.eval(wi, wo) * wi[:, 2:3], rtol=1e-12, atol=0)

    # The CLI's samples (its own RNG): our pdf at its wi is its pdf, our eval_cos/pdf its weight.
    rows = np.array([[float(x) for x in line.split(",")]
                     for line in run(cli, "sample", demo_table, "--wo", "0.3,0.1,0.9", "-n", "200").stdout.splitlines()[1:]])
    wo_rows = np.tile(np.array([0.3, 0.1, 0.9]) / np.linalg.norm([0.3, 0.1, 0.9]), (len(rows), 1))
    ok = rows[:, 3] > 0
    assert ok.sum() > 150
    assert np.allclose(demo.pdf(wo_rows[ok], rows[ok, :3]), rows[ok, 3], rtol=1e-9)
    weight = demo.eval_cos(rows[ok, :3], wo_rows[ok]) / rows[ok, 3:4]
    assert np.allclose(weight, rows[ok, 4:], rtol=1e-9)

    # Our own samples: shapes, pdf consistent with pdf(), weight with eval_cos / pdf.
    u = rng.uniform(size=(1000, 2))
    s_wi, s_pdf, s_weight = demo.sample(wo, u)
    assert s_wi.shape == (1000, 3) and s_pdf.shape == (1000,) and s_weight.shape == (1000, 3)
    good = s_pdf > 0
    assert good.mean() > 0.9 and (s_weight[~good] == 0).all()
    assert np.allclose(demo.pdf(wo[good], s_wi[good]), s_pdf[good], rtol=1e-9)
    assert np.allclose(s_weight[good], demo.eval_cos(s_wi[good], wo[good]) / s_pdf[good, None], rtol=1e-9)


def test_layouts_and_dtypes_give_the_same_result(demo):
    rng = np.random.default_rng(4)
    wi, wo = random_dirs(rng, 300), random_dirs(rng, 300)
    ref = demo.eval(wi, wo)
    assert np.array_equal(demo.eval(np.asfortranarray(wi), wo), ref)
    assert np.array_equal(demo.eval(wi.astype(">f8"), wo), ref)
    wide = np.zeros((300, 6))
    wide[:, ::2] = wi  # a strided (non-contiguous) view
    assert np.array_equal(demo.eval(wide[:, ::2], wo), ref)
    assert np.array_equal(demo.eval(wi[::-1], wo[::-1]), ref[::-1])
    assert demo.eval(np.empty((0, 3)), np.empty((0, 3))).shape == (0, 3)
    assert demo.pdf(np.empty((0, 3)), np.empty((0, 3))).shape == (0,)


@pytest.mark.parametrize("bad, message", [
    (np.zeros((4,)), r"wi: expected shape \(\.\.\., 3\), got \(4,\)"),
    (np.zeros((4, 4)), r"wi: expected shape \(\.\.\., 3\), got \(4, 4\)"),
    (np.zeros((2, 5, 3)) + 1, r"shapes do not broadcast: wi \(2, 5, 3\) and wo \(4, 3\)"),
    (np.zeros((4, 3), dtype=np.int64), "wi: expected float32 or float64, got int64"),
    (np.zeros((4, 3), dtype=np.float16), "wi: expected float32 or float64, got float16"),
    ([["0", "0", "x"]] * 4, r"wi: expected a numpy array, list or tuple of shape \(\.\.\., 3\)"),
    (np.array([[0, 0, 1], [0, 0, 0], [0, 0, 1], [0, 0, 1]], dtype=float), r"wi\[1\]: direction must be a finite non-zero vector"),
    (np.array([[0, 0, 1], [0, 0, 1], [np.nan, 0, 1], [0, 0, 1]]), r"wi\[2\]: direction must be a finite non-zero vector"),
    (np.zeros((5, 3)) + [0, 0, 1], r"wi and wo have different lengths \(5 and 4\)"),
])
def test_bad_arrays_raise_value_error(demo, bad, message):
    wo = np.tile([0.0, 0.0, 1.0], (4, 1))
    with pytest.raises(ValueError, match=message):
        demo.eval(bad, wo)
    with pytest.raises(ValueError, match=message.replace("wi", "wo").replace("wo and wo", "wo and wi")
                       .replace(r"and wo \(", r"and wi \(")):
        demo.pdf(bad, wo)
    with pytest.raises(ValueError):
        demo.sample(wo, np.zeros((4, 3)))  # u must be (N, 2)


def test_errors_carry_the_cli_message(cli, demo_table, tmp_path):
    missing = tmp_path / "missing.binary"
    with pytest.raises(FileNotFoundError) as e:
        brdfz.load(missing)
    assert str(e.value) == cli_error(cli, "info", missing)

    truncated = tmp_path / "truncated.binary"
    truncated.write_bytes(demo_table.read_bytes()[:1000])
    with pytest.raises(brdfz.FormatError) as e:
        brdfz.load(truncated)
    assert isinstance(e.value, ValueError) and str(e.value) == cli_error(cli, "info", truncated)

    unknown = tmp_path / "table.xyz"
    unknown.write_bytes(b"0")
    with pytest.raises(ValueError) as e:
        brdfz.load(unknown)
    assert str(e.value) == cli_error(cli, "info", unknown)

    with pytest.raises(ValueError) as e:
        brdfz.fit(demo_table, "lambert+nosuchlobe")
    assert str(e.value) == cli_error(cli, "fit", demo_table, "--model", "lambert+nosuchlobe", "-o", tmp_path / "m.json")

    with pytest.raises(ValueError, match="unknown representation 'nosuch'"):
        brdfz.compress(brdfz.load(demo_table), "nosuch:rank=4")
    with pytest.raises(ValueError, match=r"grid 0x90x180: every axis must be in \[1, 4096\]"):
        brdfz.tabulate(brdfz.load(demo_table), (0, 90, 180))
    with pytest.raises(ValueError, match="lookup"):
        brdfz.load(demo_table, lookup="cubic")
    with pytest.raises(TypeError, match="expected a brdfz.Brdf or a path"):
        brdfz.metrics(42, brdfz.load(demo_table))

    # A write into a missing folder is an OSError and leaves nothing behind.
    with pytest.raises(OSError):
        brdfz.save(brdfz.load(demo_table), tmp_path / "no" / "such" / "dir" / "x.binary")
    assert not (tmp_path / "no").exists()


def test_unsupported_files_raise_unsupported_error(tmp_path):
    dat = tmp_path / "m.dat"
    dat.write_text("#DIM 4 3\n0 0 0 0 1 1 1\n")
    with pytest.raises(brdfz.UnsupportedError) as e:
        brdfz.load(dat)
    assert isinstance(e.value, ValueError) and "m.dat" in str(e.value)


def test_save_load_round_trips(demo, tmp_path):
    rng = np.random.default_rng(5)
    wi, wo = random_dirs(rng, 500), random_dirs(rng, 500)
    for name in ["t.binary", "t.brdfz", "t.exr"]:
        counts = brdfz.save(demo, tmp_path / name)
        assert counts["valid"] > 0
        assert np.array_equal(brdfz.load(tmp_path / name).eval(wi, wo), demo.eval(wi, wo)), name
    model = brdfz.fit(demo, "lambert+ggx", starts=2).brdf
    for name in ["m.json", "m.brdfz"]:
        brdfz.save(model, tmp_path / name)
        back = brdfz.load(tmp_path / name)
        assert back.parameters == model.parameters
        assert np.array_equal(back.eval(wi, wo), model.eval(wi, wo))


def test_export_writes_the_representation(demo, tmp_path):
    rng = np.random.default_rng(6)
    wi, wo = random_dirs(rng, 500), random_dirs(rng, 500)
    r = brdfz.export(demo, tmp_path / "t.brdfzrt", repr="tabular:res=8x8x16,dtype=f16")
    assert "f16" in r["describe"] or "float16" in r["describe"], r
    small = brdfz.compress(demo, "tabular:res=8x8x16,dtype=f16")
    assert np.allclose(brdfz.load(tmp_path / "t.brdfzrt").eval(wi, wo), small.eval(wi, wo), rtol=1e-6, atol=0)


def test_convert_equals_cli(cli, demo_table, tmp_path):
    counts = brdfz.convert(demo_table, tmp_path / "py.binary", res=(45, 45, 90))
    run(cli, "convert", demo_table, tmp_path / "cli.binary", "--res", "45x45x90")
    assert (tmp_path / "py.binary").read_bytes() == (tmp_path / "cli.binary").read_bytes()
    assert counts["valid"] == brdfz.load(tmp_path / "py.binary").table.shape[0] * 45 * 90 - counts["below_horizon"]


def test_tabulate_equals_cli_resampling(cli, demo_table, demo, tmp_path):
    table = brdfz.tabulate(demo, (45, 45, 90))
    assert table.nbytes == 45 * 45 * 90 * 3 * 4 and table.channels == 3
    assert table.table.shape == (45, 45, 90, 3) and table.table.dtype == np.float32
    assert not table.table.flags.writeable
    run(cli, "convert", demo_table, tmp_path / "cli.brdfz", "--res", "45x45x90")
    assert np.array_equal(table.table, brdfz.load(tmp_path / "cli.brdfz").table, equal_nan=True)
    assert demo.table.shape == (90, 90, 180, 3)
    view = table.table
    del table  # the view keeps its Brdf alive
    assert np.isfinite(view).sum() > 0


def test_metrics_equal_cli_diff(cli, demo_table, demo, tmp_path):
    brdfz.save(brdfz.tabulate(demo, (30, 30, 60)), tmp_path / "coarse.binary")
    coarse = brdfz.load(tmp_path / "coarse.binary")
    m = brdfz.metrics(demo, coarse)
    ref = json.loads(run(cli, "diff", demo_table, tmp_path / "coarse.binary", "--json").stdout)
    for key in ["cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"]:
        for c in ["r", "g", "b", "mean"]:
            assert getattr(getattr(m, key), c) == pytest.approx(ref[key][c], rel=1e-12), (key, c)
    assert m.samples == ref["samples"] and m.to_dict()["log_rmse"]["mean"] == m.log_rmse.mean
    nearest = brdfz.load(demo_table, lookup="nearest")
    assert brdfz.metrics(nearest, nearest).cos_rmse.mean == 0


def test_compress_report(demo):
    table = brdfz.compress(demo, "tabular:res=45x45x90")
    assert isinstance(table, brdfz.Brdf) and table.nbytes == 45 * 45 * 90 * 3 * 4
    built = brdfz.compress(demo, "tabular:res=45x45x90", report=True)
    assert built.spec == "tabular:res=45x45x90" and built.build_seconds > 0 and isinstance(built.notes, list)
    assert "45x45x90" in built.brdf.describe()
    fitted = brdfz.compress(demo, "analytic:lambert+ggx,starts=2", report=True)
    assert fitted.brdf.parameters is not None and any(n.startswith("fit ") for n in fitted.notes)


def test_compress_equals_cli(cli, demo_table, demo, tmp_path):
    out = tmp_path / "cli.brdfz"
    r = json.loads(run(cli, "compress", demo_table, "-o", out, "--repr", "tabular:res=16x16x32", "--json").stdout)
    built = brdfz.compress(demo, "tabular:res=16x16x32", report=True)
    assert built.spec == r["repr"] and built.brdf.nbytes == r["bytes"]
    assert np.array_equal(built.brdf.table, brdfz.load(out).table, equal_nan=True)
    for spec in ["tabular:res=16x16", "tabular:rez=16x16x32", "tabular:dtype=f64", "analytic"]:
        with pytest.raises(ValueError) as e:
            brdfz.compress(demo, spec)
        assert str(e.value) == cli_error(cli, "compress", demo_table, "-o", tmp_path / "never.brdfz", "--repr", spec)
    assert not (tmp_path / "never.brdfz").exists()


def test_fit_report_matches_cli(cli, demo_table, demo, tmp_path):
    r = brdfz.fit(demo, "lambert+ggx", loss="log", starts=4, seed=3, threads=1)
    ref = json.loads(run(cli, "fit", demo_table, "--model", "lambert+ggx", "--starts", "4", "--seed", "3",
                         "--threads", "1", "-o", tmp_path / "m.json", "--json", check=False).stdout)
    assert r.report.status == ref["status"] and r.report.message == ref["message"]
    assert r.report.model == "lambert+ggx" and r.report.loss == "log"
    assert r.brdf.parameters == pytest.approx(ref["parameters"], rel=1e-9)
    assert r.report.metrics.cos_rmse_rel.mean == pytest.approx(ref["metrics"]["cos_rmse_rel"]["mean"], rel=1e-9)
    assert r.report.samples == ref["samples"] and r.report.seconds > 0
    assert r.report.poor_fit == ref["poor_fit"]


def test_progress(demo, capsys):
    seen = []
    brdfz.tabulate(demo, (20, 20, 40), progress=seen.append)
    assert seen and seen == sorted(seen) and seen[-1] == 1.0 and all(0 < f <= 1 for f in seen)

    brdfz.fit(demo, "lambert", starts=1, progress=True)
    err = capsys.readouterr().err
    assert "fitting" in err and "100%" in err

    def fail(fraction):
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        brdfz.compress(demo, "tabular:res=20x20x40", progress=fail)
    with pytest.raises(ValueError, match="progress"):
        brdfz.tabulate(demo, (20, 20, 40), progress="yes")


def test_albedo_equals_cli_info(cli, demo_table, demo):
    info = json.loads(run(cli, "info", demo_table, "--json").stdout)
    a = brdfz.albedo(demo, 0.0)
    assert a.shape == (3,) and (a > 0).all() and (a < 1).all()
    thetas = np.radians([0.0, 30.0, 60.0])
    assert brdfz.albedo(demo, thetas).shape == (3, 3)
    assert np.array_equal(brdfz.albedo(demo, thetas)[0], a)
    with pytest.raises(ValueError, match="theta_o"):
        brdfz.albedo(demo, 2.0)
    assert "albedo" in json.dumps(info)


def test_describe_channels_repr(demo):
    assert demo.channels == 3 and demo.nbytes == 90 * 90 * 180 * 3 * 4
    assert demo.describe() in repr(demo) and demo.parameters is None


def test_eval_releases_the_gil(demo):
    """While one thread evaluates a large batch, another Python thread keeps running: the longest
    pause of a counting loop during the evaluation is far shorter than the evaluation."""
    rng = np.random.default_rng(6)
    wi = np.tile(random_dirs(rng, 1000), (3000, 1))  # 3 M pairs, about 0.2-1 s
    wo = np.roll(wi, 1, axis=0)
    stamps, done = [], threading.Event()

    def count():
        while not done.is_set():
            stamps.append(time.perf_counter())

    ticker = threading.Thread(target=count)
    ticker.start()
    time.sleep(0.05)
    t0 = time.perf_counter()
    demo.eval(wi, wo)
    t1 = time.perf_counter()
    done.set()
    ticker.join()
    inside = np.array([t for t in stamps if t0 <= t <= t1])
    gaps = np.diff(np.concatenate([[t0], inside, [t1]]))
    assert t1 - t0 > 0.1, "the batch is too small to tell"
    assert len(inside) > 100 and gaps.max() < 0.5 * (t1 - t0), (t1 - t0, gaps.max(), len(inside))


def test_stubs_are_current(tmp_path):
    """bindings/python/brdfz/_core.pyi is what pybind11-stubgen makes of the built module
    (regenerate with scripts/python-stubs)."""
    stubgen = pytest.importorskip("pybind11_stubgen", reason="pybind11-stubgen is not installed")
    import pathlib
    import subprocess
    import sys

    subprocess.run([sys.executable, "-m", stubgen.__name__, "brdfz._core", "-o", str(tmp_path)], check=True,
                   capture_output=True)
    committed = pathlib.Path(__file__).resolve().parents[2] / "bindings" / "python" / "brdfz" / "_core.pyi"
    assert (tmp_path / "brdfz" / "_core.pyi").read_text() == committed.read_text(), "run scripts/python-stubs"


def test_simd_names_the_batch_kernels_instruction_set():
    assert brdfz.simd() in ("avx512", "avx2", "sse2", "sve2", "sve", "neon")
    assert "simd" in brdfz.__all__
