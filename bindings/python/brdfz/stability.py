"""The stability study (docs/stability.md) on brdfz.batch: bench/stability once per (material, spec).

    python -m brdfz.stability --program BUILD/bench/stability --out DIR [FILE ...] [--specs SPEC ...]
                              [--synthetic NAME ... | --no-synthetic] [--workers N | --scheduler ADDR]
                              [--force] ...

Materials: the program's synthetic classes (all, or those of --synthetic; none with --no-synthetic)
and the FILEs; settings: --specs, else the program's own list (`stability --list`). Each task runs
`stability --spec SPEC --synthetic NAME` (or `--synthetic none FILE`) and keeps its row as
DIR/parts/<material>/<spec-hash>.json; a rerun reuses it while the program, the file and the spec
are unchanged (--force runs everything again). A material the program cannot read fails its own
tasks. Writes DIR/stability.csv (bench/stability's columns, material by material in the settings'
order), DIR/stability.log (the program's line per row), DIR/table.md and DIR/stability_heatmap.png
(brdfz.stability_charts).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
from typing import Any, Dict, List, Optional, Sequence, Tuple

import brdfz
from brdfz import batch, report, stability_charts

COLUMNS = stability_charts.COLUMNS
# The size of a synthetic class's table as the program holds it (90x90x180 RGB doubles), for the
# task's memory estimate.
SYNTHETIC_BYTES = 90 * 90 * 180 * 3 * 8

Row = Dict[str, str]


def listing(program: str) -> Tuple[List[str], List[str]]:
    """The program's synthetic classes and default specs."""
    out = subprocess.run([program, "--list"], capture_output=True, text=True, check=True, timeout=60).stdout
    pairs = [line.split(" ", 1) for line in out.splitlines() if " " in line]
    return [v for k, v in pairs if k == "synthetic"], [v for k, v in pairs if k == "spec"]


def _record(out_dir: str, material: str, spec: str) -> pathlib.Path:
    return pathlib.Path(out_dir) / "parts" / material / f"{batch.spec_hash(spec)}.json"


def failed_row(material: str, file: Optional[str], spec: str, error: str) -> Row:
    cls = material if file is None else "real: " + pathlib.Path(file).suffix
    return dict.fromkeys(COLUMNS, "") | {"material": material, "class": cls, "repr": spec,
                                         "status": "error: " + error, "flags": "failed"}


def stability_task(program: str, material: str, file: Optional[str], spec: str, out_dir: str,
                   fingerprint: Dict[str, Any]) -> Dict[str, Any]:
    """One (material, spec) of the study, run on a worker: {"row": the program's CSV row, "log": its
    line}. A program that fails gives a row with status "error: <its message>"."""
    record = _record(out_dir, material, spec)
    record.parent.mkdir(parents=True, exist_ok=True)
    record.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        part = pathlib.Path(tmp) / "row.csv"
        which = ["--synthetic", material] if file is None else ["--synthetic", "none", file]
        proc = subprocess.run([program, "--out", str(part), "--spec", spec, *which], capture_output=True, text=True)
        rows = list(csv.DictReader(part.open(newline=""))) if part.exists() else []
    lines = [line for line in proc.stderr.splitlines() if line.strip() and not line.startswith("wrote ")]
    if proc.returncode != 0 or len(rows) != 1:
        error = lines[-1] if lines else f"{program} exited with status {proc.returncode}"
        return {"row": failed_row(material, file, spec, error), "log": f"{material} {spec} {error}"}
    result = {"row": rows[0], "log": lines[-1] if lines else ""}
    batch._write_json(record, {"fingerprint": fingerprint, **result})
    return result


def reusable(out_dir: str, material: str, spec: str, fingerprint: Dict[str, Any]) -> Optional[Dict[str, Any]]:
    try:
        doc = json.loads(_record(out_dir, material, spec).read_text())
        return {"row": doc["row"], "log": doc["log"]} if doc["fingerprint"] == fingerprint else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def run(program: str, files: Sequence[os.PathLike], out: os.PathLike, *, specs: Optional[Sequence[str]] = None,
        synthetic: Optional[Sequence[str]] = None, force: bool = False, engine: Optional[batch.Engine] = None,
        charts: bool = True) -> List[Row]:
    """The study into `out`, as the command runs it; returns the CSV's rows. `synthetic`: the classes to
    include (None: all the program has)."""
    program = str(pathlib.Path(program).resolve())
    classes, default_specs = listing(program)
    unknown = set(synthetic or []) - set(classes)
    if unknown:
        raise ValueError(f"no synthetic class {', '.join(sorted(unknown))} (the program has {', '.join(classes)})")
    specs = list(dict.fromkeys(specs or default_specs))
    named = batch.material_names(batch.material_files(files))
    clash = set(named) & set(classes if synthetic is None else synthetic)
    if clash:
        raise ValueError(f"files named like synthetic classes: {', '.join(sorted(clash))}")
    materials: Dict[str, Optional[pathlib.Path]] = {n: None for n in (classes if synthetic is None else synthetic)}
    materials |= named
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    program_sha = batch.file_sha256(program)
    results: Dict[Tuple[str, str], Dict[str, Any]] = {}
    jobs = []
    for name, file in materials.items():
        digest = batch.file_sha256(file) if file else ""
        size = file.stat().st_size if file else SYNTHETIC_BYTES
        for spec in specs:
            fp = {"program_sha256": program_sha, "input_sha256": digest, "spec": spec,
                  "brdfz_version": brdfz.__version__}
            done = None if force else reusable(str(out), name, spec, fp)
            if done is not None:
                results[(name, spec)] = done
            else:
                jobs.append(batch.Job(stability_task, (program, name, str(file) if file else None, spec, str(out), fp),
                                      f"{name} {spec}", batch.estimate_memory(size, spec), f"{name}/{batch.spec_hash(spec)}"))
    print(f"stability: {len(jobs)} tasks to run, {len(results)} finished before", file=sys.stderr)
    own = engine is None
    engine = engine or batch.Engine()
    try:
        for job, result, error in engine.map(jobs, "stability"):
            name, file, spec = job.args[1], job.args[2], job.args[3]
            results[(name, spec)] = result if not error else {"row": failed_row(name, file, spec, error),
                                                              "log": f"{name} {spec} {error}"}
    finally:
        if own:
            engine.close()
        order = [(n, s) for n in materials for s in specs if (n, s) in results]
        rows = [results[k]["row"] for k in order]
        report.write_csv(rows, out / "stability.csv", COLUMNS)
        report.atomic_write(out / "stability.log", lambda f: f.write("".join(results[k]["log"] + "\n" for k in order)))
    report.atomic_write(out / "table.md", lambda f: f.write(stability_charts.markdown_table(rows)))
    if charts and rows:
        stability_charts.heatmap(out / "stability.csv", out / "stability_heatmap.png")
    return rows


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m brdfz.stability", description=__doc__.split("\n\n")[0])
    p.add_argument("files", nargs="*", metavar="FILE", help="real BRDF files (or folders of them) besides the synthetic classes")
    p.add_argument("--program", required=True, help="the bench/stability program of a build")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--specs", nargs="+", metavar="SPEC", help="settings (default: the program's list)")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--synthetic", nargs="+", metavar="NAME", help="only these synthetic classes")
    which.add_argument("--no-synthetic", action="store_true", help="no synthetic classes, only the files")
    batch.engine_arguments(p)
    args = p.parse_args(argv)
    try:
        with batch.engine_of(args) as engine:
            rows = run(args.program, args.files, args.out, specs=args.specs,
                       synthetic=[] if args.no_synthetic else args.synthetic, force=args.force, engine=engine)
    except KeyboardInterrupt:
        print(f"stability: interrupted; {pathlib.Path(args.out) / 'stability.csv'} holds the tasks that finished",
              file=sys.stderr)
        return 130
    except (ValueError, OSError, RuntimeError, subprocess.SubprocessError) as e:
        print(f"stability: {e}", file=sys.stderr)
        return 1
    failed = sum(r["status"].startswith("error") for r in rows)
    print(f"stability: {len(rows)} rows ({failed} failed builds) in {pathlib.Path(args.out)}: stability.csv, "
          "stability.log, table.md, stability_heatmap.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
