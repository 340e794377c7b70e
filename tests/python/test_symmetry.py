"""Non-reciprocal tables (symmetry=none) and the reciprocity error from Python and the command: the
spec key, brdfz.tabulate(symmetry=), `brdfz info` / `validate` and brdfz.reciprocity_error, and on a
real RGL file a symmetry=none table following what a reciprocal one cannot."""
import json

import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()


def test_tabulate_and_compress_take_symmetry(demo_table):
    m = brdfz.load(demo_table)
    t = brdfz.tabulate(m, (16, 16, 32), symmetry="none")
    assert t.table.shape == (16, 16, 32, 3)
    assert "symmetry none" in t.describe()
    c = brdfz.compress(m, "tabular:res=16x16x32,symmetry=none")
    assert "symmetry none" in c.describe()
    with pytest.raises(ValueError, match="reciprocal"):
        brdfz.tabulate(m, (8, 8, 8), symmetry="mirror")
    with pytest.raises(ValueError, match="reciprocal, none"):
        brdfz.compress(m, "svd:rank=2,symmetry=both")


def test_info_and_validate_report_the_reciprocity_error(cli, demo_table, rgl_files, tmp_path):
    # A MERL table is reciprocal by construction; an RGL file is not.
    merl = json.loads(run(cli, "info", demo_table, "--json").stdout)
    assert merl["reciprocity_error"] < 1e-6
    path = next(p for p in rgl_files if p.name == "satin_rosaline_rgb.bsdf")
    rgl = json.loads(run(cli, "info", path, "--json").stdout)
    assert rgl["reciprocity_error"] > 0.1
    assert rgl["reciprocity_error"] == pytest.approx(brdfz.reciprocity_error(brdfz.load(path)).cos_rmse_rel.mean,
                                                     rel=1e-12)
    assert "reciprocity error" in run(cli, "info", path).stdout
    v = json.loads(run(cli, "validate", path, "--json", check=False).stdout)
    assert v["reciprocity"]["error"] == pytest.approx(rgl["reciprocity_error"], rel=1e-12)
    assert "error" not in v["energy"] and "error" not in v["non-negativity"]
    assert "      error " in run(cli, "validate", path, check=False).stdout
    report = brdfz.validate(brdfz.load(path))
    assert report["reciprocity"].error == pytest.approx(rgl["reciprocity_error"], rel=1e-12)
    assert report["energy"].error is None
    assert report.to_dict()["reciprocity"]["error"] == report["reciprocity"].error


def test_a_symmetry_none_table_follows_a_non_reciprocal_file(rgl_files, tmp_path):
    path = next(p for p in rgl_files if p.name == "satin_rosaline_rgb.bsdf")
    m = brdfz.load(path)
    none = brdfz.compress(m, "tabular:res=45x45x180,symmetry=none")
    folded = brdfz.compress(m, "tabular:res=45x45x90")
    e_none = brdfz.metrics(m, none, over="directions", directions=1 << 16).cos_rmse_rel.mean
    e_folded = brdfz.metrics(m, folded, over="directions", directions=1 << 16).cos_rmse_rel.mean
    assert e_none < 0.03 < 0.2 < e_folded
    out = tmp_path / "none.brdfz"
    brdfz.save(none, out)
    back = brdfz.load(out)
    assert back.describe() == none.describe()
    assert brdfz.metrics(none, back, over="directions", directions=4096).cos_rmse.mean == 0.0
