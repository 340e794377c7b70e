"""python -m brdfz.bench (on brdfz.batch, two Dask workers) and brdfz.stability_charts on tiny inputs: the
CSV's exact columns and rows (equal to bench/compress_sweep's where both measure the same thing), the
charts, renders and summary, and the Pareto front."""
import csv
import os
import pathlib
import re

import pytest

from conftest import import_brdfz

brdfz = import_brdfz()
pytest.importorskip("matplotlib", reason="matplotlib is not installed (scripts/setup-deps)")
pytest.importorskip("distributed", reason="Dask is not installed (scripts/setup-deps)")
bench = pytest.importorskip("brdfz.bench")
report = pytest.importorskip("brdfz.report")
stability_charts = pytest.importorskip("brdfz.stability_charts")

COLUMNS = ["material", "format", "repr", "describe", "bytes", "input_bytes", "ratio", "cos_rmse", "cos_rmse_rel",
           "log_rmse", "cbrt_rmse", "eval_pairs_per_s", "build_s", "status"]
SPECS = ["tabular:res=8x8x16", "nosuch:x=1", "tabular:res=16x16x32"]
# The measured columns; eval speed and build time differ from run to run.
DETERMINISTIC = [c for c in COLUMNS if c not in ("eval_pairs_per_s", "build_s")]


def read(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


def is_png(path):
    return path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_pareto_front():
    xs = [1, 2, 3, 4, 5, 2, 6]
    ys = [5, 3, 4, 1, 1, 3, 0.5]
    # (3, 4) is beaten by (2, 3); (5, 1) by (4, 1); the second (2, 3) repeats the first.
    assert report.pareto_front(xs, ys) == [0, 1, 3, 6]
    # Larger x is better: (6, 0.5) beats everything.
    assert report.pareto_front(xs, ys, maximize_x=True) == [6]
    assert report.pareto_front([1, 2, 3], [3, 2, 1], maximize_x=True) == [2]
    assert report.pareto_front([1, 2, 3], [1, 2, 3], maximize_x=True) == [2, 1, 0]
    assert report.pareto_front([], []) == []


def test_method_groups_tables_by_stored_type():
    assert report.method("tabular:res=45x45x90,dtype=u8log") == "tabular u8log"
    assert report.method("tabular:res=45x45x90") == "tabular"
    assert report.method("analytic:lambert+ggx") == "analytic"


@pytest.fixture(scope="module")
def bench_out(demo_table, tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    assert bench.main(["--materials", str(demo_table), "--specs", *SPECS, "--out", str(out), "--budgets", "0.5", "1e-9",
                       "--candidates", "tabular:res=8x8x16", "tabular:res=16x16x32", "--render-size", "24",
                       "--workers", "2"]) == 0
    return out


def test_bench_csv(bench_out, demo_table):
    rows = read(bench_out / "sweep.csv")
    assert rows[0] == COLUMNS + (bench.DIRECTIONS_COLUMNS if bench.batch.measures_directions() else [])
    assert [(r[0], r[1], r[2]) for r in rows[1:]] == [("coated-diffuse", "merl", s) for s in SPECS]
    size = os.path.getsize(demo_table)
    demo = brdfz.load(demo_table)
    for r in (rows[1], rows[3]):
        d = dict(zip(COLUMNS, r))
        t = brdfz.trial(demo, d["repr"])
        assert d["status"] == "ok" and d["describe"] == t.describe and int(d["bytes"]) == t.bytes
        assert int(d["input_bytes"]) == size and float(d["ratio"]) == pytest.approx(size / t.bytes, rel=1e-5)
        assert float(d["cos_rmse_rel"]) == pytest.approx(t.metrics.cos_rmse_rel.mean, rel=1e-5)
        assert float(d["log_rmse"]) == pytest.approx(t.metrics.log_rmse.mean, rel=1e-5)
        assert float(d["eval_pairs_per_s"]) > 0 and float(d["build_s"]) > 0
    failed = dict(zip(COLUMNS, rows[2]))
    assert failed["status"].startswith("error: unknown representation 'nosuch'")
    assert failed["input_bytes"] == str(size) and all(failed[c] == "" for c in ("bytes", "ratio", "cos_rmse_rel"))


def test_bench_csv_equals_compress_sweep(bench_out, demo_table, cli, tmp_path):
    """The C++ sweep writes the same columns and, but for timings, the same values."""
    sweep = pathlib.Path(cli).resolve().parents[2] / "bench" / "compress_sweep"
    if not sweep.exists():
        pytest.skip("bench/compress_sweep is not built (BRDFZ_BUILD_BENCH=OFF)")
    import subprocess

    out = tmp_path / "cpp.csv"
    subprocess.run([sweep, "--out", out, *[a for s in SPECS for a in ("--spec", s)], demo_table], check=True,
                   capture_output=True, timeout=300)
    cpp, py = read(out), read(bench_out / "sweep.csv")
    assert cpp[0] == py[0][:len(COLUMNS)] == COLUMNS and len(cpp) == len(py)
    keep = [COLUMNS.index(c) for c in DETERMINISTIC]
    assert [[r[i] for i in keep] for r in cpp] == [[r[i] for i in keep] for r in py]
    # --from-csv draws the same charts from the C++ program's file.
    charts = tmp_path / "charts"
    assert bench.main(["--from-csv", str(out), "--out", str(charts), "--budgets"]) == 0
    assert is_png(charts / "size_vs_cos_rmse_rel.png") and (charts / "summary.md").exists()
    assert not (charts / "auto.csv").exists()


def test_bench_charts_renders_summary(bench_out):
    pngs = ["size_vs_cos_rmse_rel.png", "size_vs_cos_rmse.png", "size_vs_log_rmse.png", "size_vs_cbrt_rmse.png",
            "speed_vs_error.png", "auto_size_vs_error.png", "auto_speed_vs_error.png", "renders/coated-diffuse.png",
            # No setting within 5 %: the material's own views, no comparison.
            "views/coated-diffuse_polar.png", "views/coated-diffuse_slices.png"]
    for p in pngs:
        assert is_png(bench_out / p), p
    summary = (bench_out / "summary.md").read_text()
    links = re.findall(r"\]\(([^)]+)\)", summary)
    assert set(pngs) | {"sweep.csv"} <= set(links)
    assert all((bench_out / link).exists() for link in links)
    # The failed setting is listed, and the auto selection's rows: a choice at 0.5, none at 1e-9.
    assert "`nosuch:x=1`" in summary and "none within the budget" in summary
    auto = read(bench_out / "auto.csv")
    assert auto[0] == bench.AUTO_COLUMNS
    assert [r[:3] for r in auto[1:]] == [["coated-diffuse", "0.5", "tabular:res=16x16x32"], ["coated-diffuse", "1e-09", ""]]
    assert auto[2][-1] == "2"  # both candidates tried


def test_views_compare_a_setting(demo_table, tmp_path):
    """With a setting to show, the views put it beside the material and draw its error."""
    from brdfz import batch

    pick = {"spec": "tabular:res=16x16x32", "bytes": "98304"}
    written = batch.views_task("coated-diffuse", str(demo_table), pick, None, str(tmp_path))
    assert [pathlib.Path(p).name for p in written] == [f"coated-diffuse_{v}.png" for v in batch.VIEWS]
    assert all(is_png(pathlib.Path(p)) for p in written)
    assert not list(tmp_path.glob(".*"))  # no temporary file left


def test_stability_heatmap(tmp_path):
    src = tmp_path / "stability.csv"
    src.write_text(
        "material,class,repr,status,bytes,cos_rmse_rel,log_rmse,grazing_ratio,sampler_variance_ratio,bad_values,"
        "eval_pairs_per_s,build_s,flags\n"
        'diffuse,diffuse,"analytic:lambert+ggx","converged",64,0.001,0.001,1,1,0,5e7,1,""\n'
        'diffuse,diffuse,"svd:rank=2","error: unknown representation",0,nan,nan,nan,nan,0,0,0,"failed"\n'
        'metal,metal,"analytic:lambert+ggx","hit_bounds",64,0.3,0.1,12,2,0,5e7,1,"hit_bounds; poor fit; grazing artefacts"\n'
        'metal,metal,"svd:rank=2","ok",1000,0.8,0.2,1,1,3,1e7,1,"error blow-up; bad values"\n')
    assert stability_charts.main([str(src), "--out", str(tmp_path / "out")]) == 0
    assert is_png(tmp_path / "out" / "stability_heatmap.png")
    assert (tmp_path / "out" / "table.md").read_text().splitlines() == [
        "| method | diffuse | metal |", "|---|---|---|",
        "| `analytic:lambert+ggx` | 0.001 | 0.3 ⚠ hit_bounds ⚠ poor fit ⚠ grazing artefacts |",
        "| `svd:rank=2` | fails | 0.8 ⚠ error blow-up ⚠ bad values |"]
    assert stability_charts.flag_letters("hit_bounds; grazing artefacts") == "FG"
    assert stability_charts.flag_letters("hit_bounds; poor fit; grazing artefacts") == "FPG"
    assert stability_charts.flag_letters("error blow-up; bad values; sampler worse than cosine") == "BVS"
    assert stability_charts.flag_letters("failed") == ""
    bad = tmp_path / "bad.csv"
    bad.write_text("material,repr\nx,y\n")
    with pytest.raises(ValueError, match="not a stability CSV"):
        stability_charts.main([str(bad)])


def test_stability_study(cli, rgl_files, tmp_path):
    """scripts/stability's driver: bench/stability once per (material, spec) on two Dask workers gives the
    rows the program's own loop gives, a corrupt file fails its own tasks only, and a rerun reuses every
    finished task."""
    program = pathlib.Path(cli).resolve().parents[2] / "bench" / "stability"
    if not program.exists():
        pytest.skip("bench/stability is not built (BRDFZ_BUILD_BENCH=OFF)")
    import subprocess

    from brdfz import batch, stability

    corrupt = tmp_path / "broken_rgb.bsdf"
    corrupt.write_bytes(rgl_files[0].read_bytes()[:50_000])
    specs = ["tabular:res=16x16x32", "bivariate:res=32x32"]
    out = tmp_path / "out"
    with batch.Engine(workers=2) as engine:
        rows = stability.run(program, [rgl_files[0], corrupt], out, specs=specs, synthetic=["diffuse"], engine=engine)
    assert [(r["material"], r["repr"]) for r in rows] == [(m, s) for m in ("diffuse", rgl_files[0].stem, "broken_rgb")
                                                          for s in specs]
    direct = tmp_path / "direct.csv"
    subprocess.run([program, "--out", direct, *[a for s in specs for a in ("--spec", s)], "--synthetic", "diffuse",
                    rgl_files[0]], check=True, capture_output=True, timeout=600)
    timings = ("eval_pairs_per_s", "build_s")
    with open(direct, newline="") as f:
        expected = [{k: v for k, v in r.items() if k not in timings} for r in csv.DictReader(f)]
    assert [{k: v for k, v in r.items() if k not in timings} for r in rows[:4]] == expected
    for r in rows[4:]:
        assert r["status"].startswith("error: ") and str(corrupt) in r["status"] and r["flags"] == "failed"
    with open(out / "stability.csv", newline="") as f:
        assert list(csv.DictReader(f)) == rows
    table = (out / "table.md").read_text()
    assert table.count("\n") == 2 + len(specs) and "| `bivariate:res=32x32` |" in table and "| fails | fails |" not in table
    assert table.splitlines()[2].endswith("| fails |")
    assert is_png(out / "stability_heatmap.png") and len((out / "stability.log").read_text().splitlines()) == 6
    records = {p: p.stat().st_mtime_ns for p in (out / "parts").rglob("*.json")}
    assert len(records) == 4  # the failed tasks keep no record, so a rerun tries them again
    assert stability.run(program, [rgl_files[0]], out, specs=specs, synthetic=["diffuse"],
                         engine=batch.Engine(workers=1), charts=False) == rows[:4]
    assert {p: p.stat().st_mtime_ns for p in (out / "parts").rglob("*.json")} == records


def test_summary_agrees_with_its_budget_choices(tmp_path):
    """summary.md's smallest settings within 2 % and 5 % take the budget choices into account: it never
    says "none" within an error where its own choice table holds a setting within it."""
    from brdfz import report

    def row(spec, size, err):
        return {"material": "paint", "spec": spec, "status": "ok", "bytes": str(size), "ratio": "1", "cos_rmse_rel": str(err),
                "log_rmse": "0.1", "eval_rate": "1e7", "build_seconds": "1", "error": ""}

    rows = [row("tabular:res=16x16x32", 98304, 0.09), row("svd:rank=1", 900, 0.2)]
    auto = [dict.fromkeys(report.AUTO_COLUMNS, "") | {"material": "paint", "budget": "0.05", "chosen": "svd:rank=4,space=log",
                                                    "bytes": "5000", "cos_rmse_rel": "0.034", "tried": "9"}]
    summary = report.write_summary(tmp_path, "t", rows, [], source="test", table="sweep.csv", auto=auto,
                                   auto_heading="choices").read_text()
    line = next(l for l in summary.splitlines() if l.startswith("| paint |"))
    assert line == "| paint | none |  | `svd:rank=4,space=log` (budget choice) | 5,000 |", line
    # Without the choices, the measured rows alone: none within either.
    alone = report.write_summary(tmp_path, "t", rows, [], source="test", table="sweep.csv").read_text()
    assert "| paint | none |  | none |  |" in alone


def test_quick_keeps_phi_d_whole_for_a_non_reciprocal_material(demo_table, rgl_files, tmp_path, monkeypatch):
    """--quick's settings fold φd by the mirror (symmetry=bilateral) for a material above
    brdfz.RECIPROCITY_THRESHOLD and are as given for a reciprocal one; the charts and summary judge
    over direction pairs, and the auto selection there too."""
    rgl = next(p for p in rgl_files if p.name == "satin_rosaline_rgb.bsdf")
    # Two cheap settings stand for QUICK_SPECS: a table that folds φd and a kind without a φd axis.
    monkeypatch.setattr(bench, "QUICK_SPECS", ["tabular:res=8x8x16", "bivariate:res=8x8"])
    out = tmp_path / "quick"
    assert bench.main(["--quick", "--materials", str(rgl), str(demo_table), "--out", str(out), "--budgets", "0.9",
                       "--candidates", "tabular:res=8x8x16,symmetry=bilateral", "--render-size", "0",
                       "--workers", "1"]) == 0
    with open(out / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [(r["material"], r["repr"]) for r in rows] == [
        (rgl.stem, "tabular:res=8x8x16,symmetry=bilateral"), (rgl.stem, "bivariate:res=8x8"),
        ("coated-diffuse", "tabular:res=8x8x16"), ("coated-diffuse", "bivariate:res=8x8")]
    # Judged over directions: the auto selection's error is the sweep's over directions for that setting.
    with open(out / "auto.csv", newline="") as f:
        auto = {r["material"]: r for r in csv.DictReader(f)}
    swept = {r["material"]: r for r in rows if r["repr"] == "tabular:res=8x8x16,symmetry=bilateral"}
    assert auto[rgl.stem]["chosen"] == "tabular:res=8x8x16,symmetry=bilateral"
    assert float(auto[rgl.stem]["cos_rmse_rel"]) == pytest.approx(float(swept[rgl.stem]["directions_cos_rmse_rel"]),
                                                                  rel=1e-5)
    summary = (out / "summary.md").read_text()
    assert "judged (fronts, smallest within an error, choices, renders) by cos_rmse_rel over direction pairs" in summary
