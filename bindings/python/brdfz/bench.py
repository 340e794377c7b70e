"""The compression benchmark: every representation setting over a set of materials, on brdfz.batch.

    python -m brdfz.bench [--materials DIR_OR_FILE ...] [--specs SPEC ...] [--out DIR] [--quick]
                          [--from-csv FILE] [--budgets E ...] [--candidates SPEC ...] [--render-size N]
                          [--workers N | --scheduler ADDR] [--force] ...

Materials default to ../shared/data/rgl/*.bsdf and the MERL tables in $BRDFZ_MERL_DIR (else
build/merl-tables), relative to the current folder (the repository root). Settings default to
brdfz.benchmark_specs(); with --quick to QUICK_SPECS, with φd kept whole (brdfz.keep_phi_d_whole:
symmetry=bilateral) for a material whose reciprocity error is above brdfz.RECIPROCITY_THRESHOLD
(quick_specs). Each (material, setting) is one brdfz.batch task (the numbers `brdfz compress` prints,
over the grid and over direction pairs); a setting that fails (e.g. a kind this build lacks) is a row
with status "error: ...". Charts, renders, views, the auto selection and summary.md judge by the
errors over direction pairs, what a renderer sees (the grid's, of a sweep CSV without them). The
renders and the auto selection are tasks too (one per material, one per material and budget). Writes
into --out (default bench-out/) the batch's outputs and catalogue.csv
(DIR/<material>/<spec-hash>.brdfz; a rerun reuses what is done, --force rebuilds), and:

    sweep.csv                    the columns of bench/compress_sweep (COLUMNS), then the errors over
                                 directions (DIRECTIONS_COLUMNS) when measured
    size_vs_<metric>.png         bytes vs each error metric, log-log, one panel per material, Pareto front marked
    speed_vs_error.png           eval speed vs cos_rmse_rel, Pareto front (fast and accurate) marked
    renders/<material>.png       a sphere under a fixed light and sky: reference, the Pareto-optimal
                                 settings and their error images (one colour scale)
    views/<material>_polar.png, _slices.png, _compare.png
                                 brdfz.plot's incidence-plane polar plots and θh×θd images of the material
                                 and its smallest setting within 2 % (else 5 %), and that setting's
                                 relative error in both (not drawn with --render-size 0)
    auto.csv, auto_size_vs_error.png, auto_speed_vs_error.png
                                 brdfz.compress(auto=True, metric="cos") at each budget (over directions,
                                 or over the grid where the sweep has only the grid's errors), the
                                 chosen representations drawn over each method's Pareto front
    summary.md                   tables and every image above

--from-csv FILE draws from an existing sweep CSV (this program's or bench/compress_sweep's) instead of
sweeping; renders and the auto selection then use the --materials files whose names match its rows.
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import sys
import time
from typing import Dict, List, Optional, Sequence

import brdfz
from brdfz import batch, report

COLUMNS = ["material", "format", "repr", "describe", "bytes", "input_bytes", "ratio", "cos_rmse", "cos_rmse_rel",
           "log_rmse", "cbrt_rmse", "eval_pairs_per_s", "build_s", "status"]
DIRECTIONS_COLUMNS = report.DIRECTIONS_METRICS
AUTO_COLUMNS = report.AUTO_COLUMNS
# --quick: one setting of each kind, small enough for a smoke run (quick_specs: per material).
QUICK_SPECS = ["tabular:res=45x45x90", "tabular:res=16x16x32,dtype=u8log", "bivariate:res=32x32,dtype=f16",
               "svd:rank=2,space=log", "nmf:rank=2", "analytic:lambert+ggx"]
DEFAULT_BUDGETS = report.DEFAULT_BUDGETS
# The sweep's column -> the catalogue's, where the names differ.
_CATALOGUE_NAME = {"repr": "spec", "eval_pairs_per_s": "eval_rate", "build_s": "build_seconds"}

Row = report.Row


def default_places() -> List[pathlib.Path]:
    """Where the default materials are looked for: the RGL files, then the MERL tables."""
    return [pathlib.Path("../shared/data/rgl"), pathlib.Path(os.environ.get("BRDFZ_MERL_DIR") or "build/merl-tables")]


def default_materials() -> List[pathlib.Path]:
    rgl, merl_dir = default_places()
    return sorted(rgl.glob("*.bsdf")) + sorted(merl_dir.glob("*.binary"))


def no_materials(given: Optional[Sequence[str]]) -> str:
    """Why no material was found: where it looked, and how to name some."""
    if given:
        return (f"no materials in {', '.join(given)}: give BRDF files or folders holding "
                f"{', '.join(sorted(batch.BRDF_SUFFIXES))} files")
    rgl, merl = (p.resolve() for p in default_places())
    return (f"no materials: looked for {rgl}/*.bsdf and {merl}/*.binary ($BRDFZ_MERL_DIR), relative to {os.getcwd()}; "
            "name them with --materials FILE_OR_DIR ...")


def missing_charts() -> Optional[str]:
    """The one line saying what to install when matplotlib, which every chart needs, is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return "python -m brdfz.bench needs matplotlib for its charts: pip install 'brdfz[bench]' (or matplotlib)"
    return None


# -------------------------------------------------------------------------------------- sweep rows

def sweep_row(row: Row) -> Row:
    """A catalogue row as a row of bench/compress_sweep's CSV (COLUMNS, then DIRECTIONS_COLUMNS)."""
    out = {c: row.get(_CATALOGUE_NAME.get(c, c)) for c in COLUMNS + DIRECTIONS_COLUMNS}
    out["status"] = ("; ".join(["ok"] + ([row["notes"]] if row.get("notes") else [])) if report.ok(row)
                     else "error: " + row["error"])
    return out


def catalogue_row(row: Row) -> Row:
    """A sweep CSV's row as a catalogue row, for the charts."""
    out = {_CATALOGUE_NAME.get(c, c): v for c, v in row.items()}
    status, _, notes = row["status"].partition("; ")
    failed = status.startswith("error")
    out |= {"status": "failed" if failed else "ok", "error": row["status"][len("error: "):] if failed else "",
            "notes": "" if failed else notes, "output": None}
    return out


def read_csv(path: pathlib.Path) -> List[Row]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = set(COLUMNS) - set(reader.fieldnames or [])
        if missing:
            raise ValueError(f"{path}: not a sweep CSV (no column {', '.join(sorted(missing))})")
        return [catalogue_row(r) for r in reader]


def quick_specs(path: pathlib.Path) -> List[str]:
    """QUICK_SPECS for one material: with φd kept whole (brdfz.keep_phi_d_whole) when its reciprocity
    error is above brdfz.RECIPROCITY_THRESHOLD, as real RGL measurements' are, since a reciprocal table
    of them holds the mean of f(wi, wo) and f(wo, wi). 2^16 pairs tell 0 from 0.1-1."""
    return QUICK_SPECS if brdfz.is_reciprocal(brdfz.load(path), directions=1 << 16) else \
        brdfz.keep_phi_d_whole(QUICK_SPECS)


# --------------------------------------------------------------------------------- auto selection

def auto_task(name: str, path: str, budget: float, candidates: Optional[Sequence[str]], threads: int,
              over: str = "directions") -> Row:
    """brdfz.compress(auto=True, metric="cos") of one material at one budget, its errors `over`
    directions or the grid, as an AUTO_COLUMNS row."""
    ref = brdfz.load(path)
    row = dict.fromkeys(AUTO_COLUMNS, "") | {"material": name, "budget": f"{budget:g}"}
    try:
        s = brdfz.compress(ref, auto=True, max_error=budget, metric="cos", candidates=candidates, report=True,
                           threads=threads, over=over)
        c = s.candidates[s.chosen]
        row |= {"chosen": c.spec, "bytes": str(c.bytes), "cos_rmse_rel": report.fmt(c.error),
                "eval_pairs_per_s": report.fmt(c.eval_rate), "build_s": report.fmt(c.build_seconds),
                "tried": str(len(s.candidates))}
    except ValueError as e:
        row["tried"] = str(len(e.selection.candidates)) if hasattr(e, "selection") else ""
    return row


def auto_selection(engine: batch.Engine, materials: Dict[str, pathlib.Path], budgets: Sequence[float],
                   candidates: Optional[Sequence[str]], over: str = "directions") -> List[Row]:
    """auto_task on every material at every budget, one task each; rows in material, budget order."""
    tried = candidates or brdfz.default_candidates()
    jobs = [batch.Job(auto_task, (name, str(path), budget, candidates, engine.task_threads(), over),
                      f"{name} budget {budget:g}", max(batch.estimate_memory(path.stat().st_size, c) for c in tried))
            for name, path in materials.items() for budget in budgets]
    done = {}
    for job, row, error in engine.map(jobs, "auto"):
        name, _, budget = job.args[:3]
        if error:
            print(f"auto: {job.label}: {error}", file=sys.stderr)
            row = dict.fromkeys(AUTO_COLUMNS, "") | {"material": name, "budget": f"{budget:g}"}
        done[(name, budget)] = row
    return [done[(n, b)] for n in materials for b in budgets]


# ---------------------------------------------------------------------------------------------- main

def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m brdfz.bench", description=__doc__.split("\n\n")[0])
    p.add_argument("--materials", nargs="+", metavar="DIR_OR_FILE", help="BRDF files or folders of them")
    p.add_argument("--specs", nargs="+", metavar="SPEC", help="settings (default: brdfz.benchmark_specs())")
    p.add_argument("--out", default="bench-out", help="output folder (default: bench-out)")
    p.add_argument("--quick", action="store_true",
                   help="one setting per kind (symmetry=bilateral for a material whose reciprocity error is above "
                        f"{brdfz.RECIPROCITY_THRESHOLD:g}), small renders, one budget")
    p.add_argument("--from-csv", metavar="FILE", help="draw from this sweep CSV instead of sweeping")
    p.add_argument("--budgets", nargs="*", type=float, metavar="E",
                   help=f"cos_rmse_rel budgets of the auto selection (default {DEFAULT_BUDGETS}; none: skip it)")
    p.add_argument("--candidates", nargs="+", metavar="SPEC", help="auto selection candidates, cheapest first "
                                                                    "(default: brdfz.default_candidates())")
    p.add_argument("--render-size", type=int, help="sphere renders' size in pixels (default 128, --quick 64; 0: none)")
    batch.engine_arguments(p)
    args = p.parse_args(argv)

    # Before any work: a sweep that ends without its charts has lost its point.
    missing = missing_charts()
    if missing:
        print(missing, file=sys.stderr)
        return 2
    started = time.monotonic()
    try:
        files = batch.material_files(args.materials) if args.materials else default_materials()
    except FileNotFoundError as e:
        p.error(str(e))
    if not files and not args.from_csv:
        p.error(no_materials(args.materials))
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    named = batch.material_names(files)
    specs = args.specs or (quick_specs if args.quick else brdfz.benchmark_specs())
    size = args.render_size if args.render_size is not None else (64 if args.quick else 128)
    budgets = args.budgets if args.budgets is not None else (DEFAULT_BUDGETS[1:] if args.quick else DEFAULT_BUDGETS)

    try:
        with batch.engine_of(args) as engine:
            if args.from_csv:
                rows = read_csv(pathlib.Path(args.from_csv))
                source = args.from_csv
            else:
                over = ("grid", "directions") if batch.measures_directions() else "grid"
                rows = batch.run(list(named.values()), specs, out, over=over, force=args.force, charts=False,
                                 engine=engine)
                source = "python -m brdfz.bench"
            report.write_csv([sweep_row(r) for r in rows], out / "sweep.csv",
                             COLUMNS + (DIRECTIONS_COLUMNS if report.has_directions(rows) else []))
            renders = batch.render_all(engine, out, rows, named, size, 32 if args.quick else 128) if size > 0 else []
            views = batch.views_all(engine, out, rows, named) if size > 0 else []
            materials = {n: f for n, f in named.items() if n in {r["material"] for r in rows}}
            auto = (auto_selection(engine, materials, budgets, args.candidates, report.frame(rows))
                    if budgets and materials else [])
    except KeyboardInterrupt:
        print(f"bench: interrupted; {out / 'catalogue.csv'} holds the tasks that finished", file=sys.stderr)
        return 130
    if auto:
        report.write_csv(auto, out / "auto.csv", AUTO_COLUMNS)
    charts = report.write_charts(out, rows, auto)
    summary = report.write_summary(out, "brdfz compression benchmark", rows, charts, source=source, table="sweep.csv",
                                   renders=renders, views=views, auto=auto,
                                   auto_heading="Budget-driven selection (`brdfz.compress(auto=True, metric=\"cos\")`)")
    print(f"bench: {len(rows)} rows in {time.monotonic() - started:.0f} s")
    print(f"  table   {out / 'sweep.csv'}")
    print(f"  charts  {', '.join(str(out / c) for c in charts)}")
    if renders:
        print(f"  renders {out / 'renders'}/ ({len(renders)} materials)")
    if views:
        print(f"  views   {out / 'views'}/ ({len(views)} images)")
    print(f"  summary {summary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
