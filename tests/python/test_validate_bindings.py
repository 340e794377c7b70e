"""brdfz.validate: the library's plausibility checks from Python, equal to `brdfz validate --json`."""
import json

import numpy as np
import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()


def cli_report(cli, path, *args):
    report = json.loads(run(cli, "validate", path, "--json", *args, check=False).stdout)
    del report["file"]
    return report


def test_equals_the_cli_on_real_files(cli, merl_tables, rgl_files):
    for path, args, kwargs in [(merl_tables[0], [], {}),
                               (rgl_files[0], ["--res", "20x20x40", "--theta", "0,45,80", "--rtol", "0.01"],
                                {"res": (20, 20, 40), "theta": [0, 45, 80], "rtol": 0.01})]:
        report = brdfz.validate(brdfz.load(path), **kwargs)
        assert report.to_dict() == cli_report(cli, path, *args), path
        assert [c.name for c in report.checks] == ["non-negativity", "reciprocity", "energy"]
        assert report.ok == all(c.ok for c in report.checks)


def test_a_plausible_table_passes_with_known_counts(demo_table):
    table = brdfz.load(demo_table)
    report = brdfz.validate(table)
    assert report.ok, report
    # Reciprocity: 17 x 17 elevation pairs x 16 azimuths; energy: the 10 default elevations.
    assert (report["reciprocity"].tested, report["energy"].tested) == (17 * 17 * 16, 10)
    assert report["reciprocity"].unit == "pairs" and report["energy"].unit == "elevations"
    # Non-negativity reads the table's own bins: those above the horizon that hold a value.
    assert 0 < report["non-negativity"].tested <= table.table.shape[0] * table.table.shape[1] * table.table.shape[2]
    assert report["non-negativity"].worst == []


def test_energy_violations_name_the_elevations(tmp_path):
    """lambert + ggx with both weights near 1 reflects more than it receives: every offence holds the
    model's albedo, viewed and lit alike (the model is reciprocal)."""
    params = {f"lambert.rho_{c}": 0.9 for c in "rgb"} | {f"ggx.ks_{c}": 0.9 for c in "rgb"}
    params |= {"ggx.alpha": 0.3, "ggx.f0": 1.0}
    path = tmp_path / "bright.json"
    path.write_text(json.dumps({"format": "brdfz-analytic", "version": 1, "model": "lambert+ggx",
                                "parameters": params}))
    model = brdfz.load(path)
    report = brdfz.validate(model, res=(16, 16, 32), theta=[0, 30, 60])
    energy = report["energy"]
    assert not report.ok and not energy.ok and report["reciprocity"].ok and report["non-negativity"].ok
    assert energy.failed == 3 and len(energy.worst) == 3
    rho = brdfz.albedo(model, np.radians([w["theta_i_deg"] for w in energy.worst]))
    for w, r in zip(energy.worst, rho):
        assert w["theta_i_deg"] == w["theta_o_deg"] and w["theta_i_deg"] in (0, 30, 60)
        assert np.allclose(w["albedo_viewed"], r, rtol=1e-12) and np.allclose(w["reflectance_lit"], r, rtol=1e-9)
        assert min(r) > 1.01
    badness = [max(w["albedo_viewed"] + w["reflectance_lit"]) for w in energy.worst]
    assert badness == sorted(badness, reverse=True)
    assert "energy" in repr(report)


def test_bad_arguments_are_value_errors(demo_table):
    table = brdfz.load(demo_table)
    for kwargs in [{"theta": [95]}, {"theta": []}, {"theta": [float("nan")]}, {"rtol": -1.0},
                   {"albedo_tol": float("nan")}, {"res": (0, 90, 180)}]:
        with pytest.raises(ValueError):
            brdfz.validate(table, **kwargs)
    with pytest.raises(KeyError):
        brdfz.validate(table, theta=[0])["furnace"]
