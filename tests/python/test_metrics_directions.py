"""Errors over direction pairs (metrics.h, Over::Directions) from Python and the command: the same
numbers from brdfz.metrics, metric_samples + metrics_at and `brdfz diff --over directions`, the
options reaching trial and compress(auto=True), and brdfz's RGL reader against Mitsuba 3's `measured`
on the metric's own pairs (the same file evaluated the same way: ~0 error)."""
import json

import numpy as np
import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()

METRIC_KEYS = {"cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse", "samples", "negatives"}


@pytest.fixture(scope="module")
def demo(demo_table):
    return brdfz.load(demo_table)


def test_metrics_over_directions_equal_cli_diff(cli, demo_table, demo, tmp_path):
    small = tmp_path / "small.brdfz"
    brdfz.save(brdfz.compress(demo, "tabular:res=8x8x16"), small)
    grid = json.loads(run(cli, "diff", demo_table, small, "--json").stdout)
    dirs = json.loads(run(cli, "diff", demo_table, small, "--json", "--over", "directions").stdout)
    assert set(grid) == set(dirs) == METRIC_KEYS
    assert dirs["samples"] == 1 << 18
    m = brdfz.metrics(demo, brdfz.load(small), over="directions")
    assert m.samples == 1 << 18
    for key in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"):
        assert getattr(m, key).mean == pytest.approx(dirs[key]["mean"], rel=1e-12)
    assert m.cos_rmse_rel.mean != pytest.approx(grid["cos_rmse_rel"]["mean"], rel=1e-3)
    few = json.loads(run(cli, "diff", demo_table, small, "--json", "--over", "directions", "--directions", "1000",
                         "--seed", "3").stdout)
    assert few["samples"] == 1000
    assert few["cos_rmse"]["mean"] == pytest.approx(
        brdfz.metrics(demo, brdfz.load(small), over="directions", directions=1000, seed=3).cos_rmse.mean, rel=1e-12)
    text = run(cli, "diff", demo_table, small, "--over", "directions").stdout
    assert "262144 direction pairs" in text
    bad = run(cli, "diff", demo_table, small, "--over", "pairs", check=False)
    assert bad.returncode != 0 and "--over" in bad.stderr
    with pytest.raises(ValueError, match="grid or directions"):
        brdfz.metrics(demo, demo, over="pairs")


@pytest.mark.parametrize("over", ["grid", "directions"])
def test_metric_samples_and_metrics_at_reproduce_metrics(demo, over):
    approx = brdfz.compress(demo, "analytic:lambert+ggx")
    wi, wo, f = brdfz.metric_samples(demo, over=over, directions=20000)
    assert wi.shape == wo.shape == f.shape and wi.shape[1] == 3
    m = brdfz.metrics(demo, approx, over=over, directions=20000)
    v = brdfz.metrics_at(wi, f, approx.eval(wi, wo))
    assert v.samples == m.samples == len(wi)
    assert v.cos_rmse_rel.mean == pytest.approx(m.cos_rmse_rel.mean, rel=1e-9)
    assert v.log_rmse.mean == pytest.approx(m.log_rmse.mean, rel=1e-9)
    with pytest.raises(ValueError, match="different lengths"):
        brdfz.metrics_at(wi[:5], f, f)


def test_trial_and_auto_take_the_domain(cli, demo_table, demo, tmp_path):
    t = brdfz.trial(demo, "tabular:res=8x8x16", over="directions", directions=5000, measure_speed=False)
    assert t.metrics.samples == 5000
    s = brdfz.compress(demo, auto=True, max_error=2.0, metric="cos", over="directions", directions=5000,
                       candidates=["tabular:res=8x8x16"], report=True)
    assert s.chosen == 0 and s.candidates[0].error == pytest.approx(t.metrics.cos_rmse_rel.mean, rel=1e-12)
    out = tmp_path / "auto.brdfz"
    r = json.loads(run(cli, "compress", demo_table, "-o", out, "--auto", "--max-error", "2.0", "--metric", "cos",
                       "--over", "directions", "--directions", "5000", "--candidate", "tabular:res=8x8x16",
                       "--json").stdout)
    assert r["over"] == "directions" and r["metrics"]["samples"] == 5000
    assert r["error"] == pytest.approx(t.metrics.cos_rmse_rel.mean, rel=1e-12)
    # The container keeps errors over the grid (formats/SPEC.md, /achieved).
    info = json.loads(run(cli, "info", out, "--json").stdout)
    grid = brdfz.metrics(demo, brdfz.load(out)).cos_rmse_rel.mean
    assert info["container"]["achieved"]["cos_rmse_rel"] == pytest.approx(grid, rel=1e-12)
    assert grid != pytest.approx(r["error"], rel=1e-3)


def test_rgl_reader_agrees_with_mitsuba_over_directions(rgl_files):
    """On the metric's pairs, Mitsuba's `measured` (si.wi = the file's incident direction = brdfz's wi;
    it returns f·cosθ of its wo) and brdfz's reader are the same function: the error is float32
    rounding. Read the other way round (si.wi = brdfz's wo) the data's non-reciprocity shows."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    for path in rgl_files:
        m = brdfz.load(path)
        wi, wo, f = brdfz.metric_samples(m, over="directions", directions=2048, seed=5)
        assert (wi[:, 2] > np.cos(np.radians(80.0))).all() and (wo[:, 2] > np.cos(np.radians(80.0))).all()
        bsdf = mi.load_dict({"type": "measured", "filename": str(path)})

        def mitsuba_f(incident, outgoing):
            out = np.empty((len(incident), 3))
            for k in range(len(incident)):
                si.wi = mi.Vector3f(*incident[k])
                v = bsdf.eval(ctx, si, mi.Vector3f(*outgoing[k]))
                out[k] = (v[0], v[1], v[2])
            return out / outgoing[:, 2:3]

        same = brdfz.metrics_at(wi, f, mitsuba_f(wi, wo))
        assert same.cos_rmse_rel.mean < 1e-5, f"{path.name}: {same}"
        swapped = brdfz.metrics_at(wi, f, mitsuba_f(wo, wi))
        assert swapped.cos_rmse_rel.mean > 0.02, f"{path.name}: {swapped}"
