"""brdfz pca-train: a basis from a directory of materials, its report, and one-line errors."""
import json

import pytest

from conftest import run


def model(alpha, r, g, b):
    return {
        "format": "brdfz-analytic",
        "version": 1,
        "model": "lambert+ggx",
        "parameters": {
            "lambert.rho_r": r, "lambert.rho_g": g, "lambert.rho_b": b,
            "ggx.ks_r": 0.5, "ggx.ks_g": 0.5, "ggx.ks_b": 0.5, "ggx.alpha": alpha, "ggx.f0": 0.04,
        },
    }


def materials(tmp_path, n=5):
    d = tmp_path / "train"
    d.mkdir()
    for i in range(n):
        (d / f"m{i}.json").write_text(json.dumps(model(0.1 + 0.1 * i, 0.2 + 0.1 * i, 0.5 - 0.05 * i, 0.3)))
    (d / "notes.txt").write_text("not a material: skipped")
    return d


def test_pca_train_writes_a_basis(cli, tmp_path):
    d = materials(tmp_path)
    out = tmp_path / "basis.brdfz"
    report = json.loads(run(cli, "pca-train", d, "-o", out, "--res", "8x8x16", "--k-max", "3", "--json").stdout)
    assert report["k_max"] == 3 and len(report["materials"]) == 5 and report["grid"] == "8x8x16"
    assert report["kept_bins"] + report["dropped_bins"] == 8 * 8 * 16 and report["dropped_bins"] > 0
    explained = report["explained_variance"]
    assert len(explained) == 3 and all(a < b for a, b in zip(explained, explained[1:])) and explained[-1] <= 1 + 1e-9
    assert report["basis_nbytes"] == (2 + 3) * 8 * 8 * 16 * 3 * 4 + 3 * 8
    assert len(report["sha256"]) == 64
    info = json.loads(run(cli, "info", out, "--json").stdout)
    assert info["container"]["representation"] == "pca"
    text = run(cli, "pca-train", d, "-o", tmp_path / "again.brdfz", "--res", "8x8x16").stdout
    assert "5 materials on 8x8x16" in text and "variance explained" in text


def test_pca_train_errors_are_one_line(cli, tmp_path):
    d = materials(tmp_path, 1)
    proc = run(cli, "pca-train", d, "-o", tmp_path / "b.brdfz", "--res", "8x8x16", check=False)
    assert proc.returncode != 0 and "at least 2 materials" in proc.stderr and proc.stderr.count("\n") == 1
    proc = run(cli, "pca-train", d, "-o", tmp_path / "b.binary", check=False)
    assert proc.returncode != 0 and ".brdfz" in proc.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    proc = run(cli, "pca-train", empty, "-o", tmp_path / "b.brdfz", check=False)
    assert proc.returncode != 0 and "no BRDF files" in proc.stderr
    assert not (tmp_path / "b.brdfz").exists()


def test_compress_with_a_basis_referenced_and_embedded(cli, tmp_path):
    d = materials(tmp_path)
    basis = tmp_path / "basis.brdfz"
    run(cli, "pca-train", d, "-o", basis, "--res", "16x16x32", "--k-max", "4")
    src = d / "m2.json"
    out = tmp_path / "out" / "m2.brdfz"
    out.parent.mkdir()
    r = json.loads(run(cli, "compress", src, "-o", out, "--repr", f"pca:basis={basis},k=3", "--json").stdout)
    assert r["bytes"] == 3 * 4 + 32
    info = json.loads(run(cli, "info", out, "--json").stdout)["container"]
    assert info["representation"] == "pca" and "pca.external-basis@2" in info["features"]
    # What was stored evaluates like what was reported, with the basis found beside (here: above) it.
    diff = json.loads(run(cli, "diff", src, out, "--json").stdout)
    assert diff["cos_rmse_rel"]["mean"] == pytest.approx(r["metrics"]["cos_rmse_rel"]["mean"], rel=1e-9)

    embedded = tmp_path / "embedded.brdfz"
    run(cli, "compress", src, "-o", embedded, "--repr", f"pca:basis={basis},k=3,store=embed")
    basis.unlink()
    assert "pca.external-basis@2" not in json.loads(run(cli, "info", embedded, "--json").stdout)["container"]["features"]
    proc = run(cli, "info", out, check=False)
    assert proc.returncode != 0 and "basis.brdfz" in proc.stderr and "not found" in proc.stderr
    assert proc.stderr.count("\n") == 1
