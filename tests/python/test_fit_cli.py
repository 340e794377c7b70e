"""`brdfz fit`: writes a model the other commands read, reports as text and JSON, and fails clearly."""
import json
import struct

from conftest import run


def test_fit_writes_a_model_that_info_eval_and_diff_read(cli, demo_table, tmp_path):
    out = tmp_path / "fit.json"
    proc = run(cli, "fit", demo_table, "--model", "lambert+ggx_dielectric", "-o", out, "--json")
    report = json.loads(proc.stdout)
    assert report["status"] in ("converged", "hit_bounds")
    assert report["output"] == str(out)
    assert set(report["parameters"]) == {"lambert.rho_r", "lambert.rho_g", "lambert.rho_b", "ggx_dielectric.ks_r",
                                         "ggx_dielectric.ks_g", "ggx_dielectric.ks_b", "ggx_dielectric.alpha",
                                         "ggx_dielectric.eta"}
    # The demo material is a GGX-coated diffuse with alpha 0.12: the coat's roughness comes back.
    assert abs(report["parameters"]["ggx_dielectric.alpha"] - 0.12) < 0.02
    assert report["metrics"]["cos_rmse_rel"]["mean"] < 0.2
    assert report["poor_fit"] is False
    model = json.loads(out.read_text())
    assert model["format"] == "brdfz-analytic" and model["model"] == "lambert+ggx_dielectric"
    assert model["provenance"]["status"] == report["status"]

    info = json.loads(run(cli, "info", out, "--json").stdout)
    assert info["format"] == "json" and info["nbytes"] == 8 * 8
    rows = run(cli, "eval", out, "--wi", "0,0,1", "--wo", "0.6,0,0.8").stdout.strip().split(",")
    assert len(rows) == 3 and all(float(v) > 0 for v in rows)
    diff = json.loads(run(cli, "diff", demo_table, out, "--json").stdout)
    assert abs(diff["cos_rmse_rel"]["mean"] - report["metrics"]["cos_rmse_rel"]["mean"]) < 1e-9

    text = run(cli, "fit", demo_table, "--model", "lambert+ggx", "--loss", "cbrt", "--starts", "2", "-o", out).stdout
    assert "status" in text and "ggx.alpha" in text and "wrote" in text


def test_fit_that_converges_to_a_poor_model_says_so(cli, demo_table, tmp_path):
    # A Blinn-Phong lobe cannot follow the demo's Fresnel-weighted GGX coat: the fit converges (its
    # status unchanged, exit 0, the model written) but is flagged as poor, with a warning saying why.
    out = tmp_path / "phong.json"
    report = json.loads(run(cli, "fit", demo_table, "--model", "lambert+blinn_phong", "-o", out, "--json").stdout)
    assert report["status"] in ("converged", "hit_bounds")
    assert report["poor_fit"] is True
    assert any(w.startswith("poor fit") for w in report["warnings"])
    assert out.exists()
    text = run(cli, "fit", demo_table, "--model", "lambert+blinn_phong", "-o", out).stdout
    assert "but poor fit" in text and "warning: poor fit" in text


def test_fit_without_usable_data_exits_1_and_writes_nothing(cli, tmp_path):
    # A MERL table with a single measured bin (all others negative = unmeasured).
    n = 90 * 90 * 180
    values = [-1.0] * n
    values[1000] = 500.0
    table = tmp_path / "one-bin.binary"
    table.write_bytes(struct.pack("<3i", 90, 90, 180) + struct.pack(f"<{3 * n}d", *(values * 3)))
    out = tmp_path / "never.json"
    proc = run(cli, "fit", table, "--model", "lambert+ggx", "-o", out, check=False)
    assert proc.returncode == 1
    assert "insufficient_data" in proc.stdout and "best #" not in proc.stdout
    assert proc.stderr.strip() == f"brdfz: {table}: insufficient data to fit lambert+ggx; nothing written"
    assert not out.exists()


def test_fit_rejects_bad_arguments_before_work(cli, demo_table, tmp_path):
    for args, message in [(["--model", "lambert+phong"], "unknown lobe 'phong'"),
                          (["--model", "lambert", "--loss", "l1"], "unknown fit loss"),
                          (["--model", "lambert", "--robust", "tukey"], "unknown robust loss")]:
        proc = run(cli, "fit", demo_table, *args, "-o", tmp_path / "m.json", check=False)
        assert proc.returncode == 1
        assert message in proc.stderr
        assert not (tmp_path / "m.json").exists()
    proc = run(cli, "fit", demo_table, "--model", "lambert", "-o", tmp_path / "m.txt", check=False)
    assert proc.returncode == 1 and "unknown file extension" in proc.stderr
