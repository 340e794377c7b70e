"""Budget-driven selection from Python against `brdfz compress --auto`: the same choice and the same
candidates, scenes given as files or dicts (one schema), and the errors."""
import json

import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()

# Cheapest first; on the demo table cos_rmse_rel is about 1.3, 0.20 and 0.045.
CANDIDATES = ["tabular:res=8x8x16", "tabular:res=16x16x32", "tabular:res=32x32x64"]
SCENE = {"name": "spot", "views": [{"axis": [0, 0, 1], "max_angle_deg": 30, "count": 64}],
         "lights": [{"direction": [0, 0.3, 1], "spread_deg": 5, "samples": 4}], "environment": {"radiance": 0.1}}


@pytest.fixture(scope="module")
def demo(demo_table):
    return brdfz.load(demo_table)


def cli_auto(cli, demo_table, tmp_path, *args, candidates=CANDIDATES):
    cands = [a for c in candidates for a in ("--candidate", c)]
    proc = run(cli, "compress", demo_table, "-o", tmp_path / "auto.brdfz", "--auto", *args, *cands, "--json",
               check=False)
    return proc.returncode, json.loads(proc.stdout)


def assert_same_candidates(selection, expected):
    assert [c.spec for c in selection.candidates] == [c["repr"] for c in expected]
    for c, e in zip(selection.candidates, expected):
        assert (c.bytes, c.accepted, c.reason) == (e["bytes"], e["accepted"], e["reason"])
        assert c.error == pytest.approx(e["error"], rel=1e-9)
        assert c.eval_rate > 0 and c.build_seconds > 0


def test_auto_equals_cli(cli, demo_table, demo, tmp_path):
    metric, budget = "cos", 0.1
    status, expected = cli_auto(cli, demo_table, tmp_path, "--max-error", budget, "--metric", metric)
    assert status == 0
    s = brdfz.compress(demo, auto=True, max_error=budget, metric=metric, candidates=CANDIDATES, report=True)
    assert isinstance(s, brdfz.Selection) and s.chosen >= 0
    assert s.candidates[s.chosen].spec == expected["chosen"]
    assert s.brdf.nbytes == expected["bytes"] and s.brdf is s.candidates[s.chosen].brdf
    assert_same_candidates(s, expected["candidates"])
    # Rejected candidates keep no Brdf; without report=True the chosen Brdf itself comes back.
    assert all(c.brdf is None for c in s.candidates if not c.accepted)
    chosen = brdfz.compress(demo, auto=True, max_error=budget, metric=metric, candidates=[expected["chosen"]])
    assert isinstance(chosen, brdfz.Brdf) and chosen.nbytes == expected["bytes"]


def test_size_budget_equals_cli(cli, demo_table, demo, tmp_path):
    """--max-bytes: the most accurate candidate within the size; with --max-error too, the smallest within
    both; the JSON keeps max_error (null without one) beside max_bytes."""
    sizes = [brdfz.trial(demo, c, measure_speed=False).bytes for c in CANDIDATES]
    budget = sizes[1]
    status, expected = cli_auto(cli, demo_table, tmp_path, "--max-bytes", budget, "--metric", "cos")
    assert status == 0 and expected["max_error"] is None and expected["max_bytes"] == budget
    s = brdfz.compress(demo, auto=True, max_bytes=budget, metric="cos", candidates=CANDIDATES, report=True)
    # The richest within the size is the most accurate here; the third is tried, found larger, and ends it.
    assert s.candidates[s.chosen].spec == expected["chosen"] == CANDIDATES[1]
    assert_same_candidates(s, expected["candidates"])
    assert "> size budget" in s.candidates[2].reason and s.brdf.nbytes <= budget
    fractions = []
    brdfz.compress(demo, auto=True, max_bytes=budget, metric="cos", candidates=CANDIDATES, progress=fractions.append)
    assert fractions == [pytest.approx(1 / 3), pytest.approx(2 / 3), 1.0]  # an accepted candidate does not end it
    # Both: the first within the error (cos about 1.3, 0.20, 0.045) that fits.
    both = brdfz.compress(demo, auto=True, max_error=0.5, max_bytes=sizes[2], metric="cos", candidates=CANDIDATES,
                          report=True)
    assert both.candidates[both.chosen].spec == CANDIDATES[1] and len(both.candidates) == 2
    status, none = cli_auto(cli, demo_table, tmp_path, "--max-bytes", sizes[1], "--max-error", 0.1, "--metric", "cos")
    assert status == 2 and none["chosen"] == ""
    with pytest.raises(ValueError, match=f"no candidate meets the budget 0.1 in cos, {sizes[1]} bytes"):
        brdfz.compress(demo, auto=True, max_error=0.1, max_bytes=sizes[1], metric="cos", candidates=CANDIDATES)
    for bad in (0, -5, 2.5):
        with pytest.raises(ValueError, match="max_bytes"):
            brdfz.compress(demo, auto=True, max_bytes=bad)


def test_scene_dict_equals_scene_file(cli, demo_table, demo, tmp_path):
    path = tmp_path / "spot.json"
    path.write_text(json.dumps({"format": "brdfz-scene", "version": 1, **SCENE}))
    status, expected = cli_auto(cli, demo_table, tmp_path, "--max-error", 0.05, "--metric", "image", "--scene", path)
    assert status == 0
    for scene in (SCENE, path, str(path), brdfz.read_scene(SCENE)):
        s = brdfz.compress(demo, auto=True, max_error=0.05, metric="image", scene=scene, candidates=CANDIDATES,
                           report=True)
        assert_same_candidates(s, expected["candidates"])
    sc = brdfz.read_scene(SCENE)
    assert (sc.name, sc.views) == ("spot", 64) and sc.samples == 64 * (4 + 64)


def test_no_candidate_within_budget_is_a_value_error(cli, demo_table, demo, tmp_path):
    cands = CANDIDATES[:1] + ["pca:basis=no-such-basis.brdfz,k=2"]  # builds fail; a misspelt one is an error
    status, expected = cli_auto(cli, demo_table, tmp_path, "--max-error", 1e-6, "--metric", "log", candidates=cands)
    assert status == 2 and expected["chosen"] == ""
    with pytest.raises(ValueError, match="no candidate meets the budget 1e-06 in log") as e:
        brdfz.compress(demo, auto=True, max_error=1e-6, candidates=cands)
    s = e.value.selection
    assert s.chosen == -1 and s.brdf is None and not any(c.accepted for c in s.candidates)
    assert [c.spec for c in s.candidates] == [c["repr"] for c in expected["candidates"]] == cands
    assert [c.reason for c in s.candidates] == [c["reason"] for c in expected["candidates"]]
    assert s.candidates[1].reason.startswith("failed: ") and "no-such-basis.brdfz" in s.candidates[1].reason


@pytest.mark.parametrize("scene, message", [
    ({"views": [{"cout": 3}]}, 'scene dict: views[0]: unknown member "cout"'),
    ({"lights": [{"direction": [0, 1]}]}, "scene dict: lights[0].direction: must have 3 numbers"),
    ({"lights": [{"intensity": -1}]}, "lights[0].intensity must be finite and >= 0"),
    ({"views": [{"count": 0}], "lights": [{}]}, "views[0].count"),
])
def test_bad_scene_dict_names_the_member(demo, scene, message):
    with pytest.raises(ValueError) as e:
        brdfz.compress(demo, auto=True, max_error=0.1, scene=scene, candidates=CANDIDATES)
    assert message in str(e.value)


def test_argument_errors(demo, tmp_path):
    with pytest.raises(ValueError, match="not both"):
        brdfz.compress(demo, "tabular:res=8x8x16", auto=True, max_error=0.1)
    for bad in (None, 0, -1, float("nan")):
        with pytest.raises(ValueError, match="max_error"):
            brdfz.compress(demo, auto=True, max_error=bad)
    with pytest.raises(ValueError, match="unknown metric"):
        brdfz.compress(demo, auto=True, max_error=0.1, metric="psnr", candidates=CANDIDATES)
    with pytest.raises(FileNotFoundError):
        brdfz.read_scene(tmp_path / "missing.json")


def test_progress_and_trial(demo, capsys):
    fractions = []
    cands = CANDIDATES[:2] + ["pca:basis=no-such-basis.brdfz,k=2"]
    brdfz.compress(demo, auto=True, max_error=0.5, metric="cos", candidates=cands, progress=fractions.append)
    assert fractions == [pytest.approx(1 / 3), 1.0]  # 1.0 once a candidate is accepted
    brdfz.compress(demo, auto=True, max_error=0.5, metric="cos", candidates=cands, progress=True)
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2 and lines[0].lstrip().startswith("[1/3] tabular:res=8x8x16") and lines[1].endswith("meets the budget")
    t = brdfz.trial(demo, "tabular:res=16x16x32")
    assert t.spec == "tabular:res=16x16x32" and t.bytes == 16 * 16 * 32 * 12 == t.brdf.nbytes
    assert t.metrics.cos_rmse_rel.mean == pytest.approx(brdfz.metrics(demo, t.brdf).cos_rmse_rel.mean, rel=1e-12)
    assert brdfz.benchmark_specs()[0] == "tabular:res=90x90x180" and brdfz.default_candidates()


def test_auto_measures_over_directions_unless_told_grid(cli, demo_table, demo, tmp_path):
    """--auto and compress(auto=True) judge over direction pairs by default, and say so; --over grid stays."""
    cand = CANDIDATES[:1]
    status, r = cli_auto(cli, demo_table, tmp_path, "--max-error", 5, "--metric", "cos", "--directions", 4096,
                         candidates=cand)
    over = brdfz.metrics(demo, brdfz.compress(demo, cand[0]), over="directions", directions=4096).cos_rmse_rel.mean
    assert status == 0 and r["over"] == "directions" and r["metrics"]["samples"] == 4096
    assert r["error"] == pytest.approx(over, rel=1e-12)
    s = brdfz.compress(demo, auto=True, max_error=5, metric="cos", directions=4096, candidates=cand, report=True)
    assert s.candidates[0].error == pytest.approx(over, rel=1e-12)
    status, g = cli_auto(cli, demo_table, tmp_path, "--max-error", 5, "--metric", "cos", "--over", "grid",
                         candidates=cand)
    grid = brdfz.metrics(demo, brdfz.compress(demo, cand[0])).cos_rmse_rel.mean
    assert status == 0 and g["over"] == "grid" and g["error"] == pytest.approx(grid, rel=1e-12)
    assert grid != pytest.approx(over, rel=1e-3)
    # Without --auto, --repr keeps the grid.
    single = json.loads(run(cli, "compress", demo_table, "-o", tmp_path / "one.brdfz", "--repr", cand[0], "--json").stdout)
    assert single["metrics"]["cos_rmse_rel"]["mean"] == pytest.approx(grid, rel=1e-12)


def test_a_non_reciprocal_source_gets_candidates_that_keep_phi_d_whole(demo, rgl_files):
    """Above RECIPROCITY_THRESHOLD (real RGL files: 0.1-1; a reciprocal table: 0) the default candidates
    fold φd by the mirror or not at all, never by reciprocity; a reciprocal source keeps them as they are."""
    rgl = brdfz.load(next(p for p in rgl_files if p.name == "satin_rosaline_rgb.bsdf"))
    few = 1 << 14
    assert brdfz.reciprocity_error(demo, directions=few).cos_rmse_rel.mean < 1e-6 < brdfz.RECIPROCITY_THRESHOLD
    assert brdfz.reciprocity_error(rgl, directions=few).cos_rmse_rel.mean > 10 * brdfz.RECIPROCITY_THRESHOLD
    assert brdfz.is_reciprocal(demo, directions=few) and not brdfz.is_reciprocal(rgl, directions=few)
    plain = brdfz.default_candidates()
    # The rgl_svd ones are an RGL file's own: the demo's table leaves them out, the RGL file keeps them.
    rgl_only = [c for c in plain if c.startswith("rgl_svd:")]
    assert rgl_only and brdfz.default_candidates(demo, directions=few) == [c for c in plain if c not in rgl_only]
    whole = brdfz.default_candidates(rgl, directions=few)
    assert len(whole) == len(plain) and whole != plain
    for spec in whole:
        kind, _, options = spec.partition(":")
        if kind in ("tabular", "svd", "nmf"):
            assert "symmetry=bilateral" in options.split(",") or "symmetry=none" in options.split(","), spec
    assert whole == brdfz.keep_phi_d_whole(plain)
