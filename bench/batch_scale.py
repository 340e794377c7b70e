"""brdfz.batch at scale: wall time against workers, the per-task costs, the scheduler's own cost per
task, and from them the wall time of a larger database on more cores.

    PYTHONPATH=build/python .venv/bin/python bench/batch_scale.py [--materials DIR_OR_FILE ...]
        [--specs SPEC ...] [--runs serial dask1 dask2] [--repeat R] [--noop N] [--project M --cores 8 64 512]

1. Each --runs entry runs batch.run of every spec on every material into a fresh folder, timed from
   the call (cluster start included) to the last row: "serial" is --workers 1 (no Dask; the library
   uses every core), "daskN" a LocalCluster of N workers, one library thread per task. The entries
   alternate, --repeat times; prints the median wall time (and its range), the tasks' summed wall
   and CPU time (medians), the speed-up of the median against the first entry's, and the load
   average over the runs.
2. The per-task cost table of the last run: per spec, the median over materials of load, build,
   measure (metrics and eval speed) and write seconds, and the CPU seconds.
3. The scheduler's cost per task: --noop N empty tasks (with a MEMORY resource, as batch tasks are)
   through Engine.map on a 2-worker LocalCluster already started: wall / N; and the cluster's start.
4. With --project M: the wall time of M materials × the specs on each of --cores, from the last
   run's mean CPU seconds per task of each spec (tasks on dedicated cores), as
       start + hashing + max(W / C + t_max, N · o)
   W the summed CPU time of the M × specs tasks, t_max the longest one (list scheduling finishes
   within W / C + t_max), N · o the scheduler's serial cost, start the cluster's start and hashing
   the driver's SHA-256 of the inputs (measured here at the inputs' size).
Materials default to ../shared/data/rgl; specs to brdfz.bench.QUICK_SPECS (one setting per kind).
"""
import argparse
import os
import statistics
import sys
import tempfile
import time

from brdfz import batch, bench


def noop(i):
    return i


def scheduler_overhead(n: int):
    """(seconds per task, cluster start seconds) on a 2-worker LocalCluster."""
    t0 = time.perf_counter()
    with batch.Engine(workers=2) as engine:
        engine.start()
        started = time.perf_counter() - t0
        jobs = [batch.Job(noop, (i,), "", 1) for i in range(n)]
        t1 = time.perf_counter()
        done = sum(1 for _ in engine_map_quiet(engine, jobs))
        per_task = (time.perf_counter() - t1) / done
    return per_task, started


def engine_map_quiet(engine, jobs):
    """Engine.map without its progress bar (thousands of lines off a terminal)."""
    stderr, sys.stderr = sys.stderr, open(os.devnull, "w")
    try:
        yield from engine.map(jobs, "noop")
    finally:
        sys.stderr.close()
        sys.stderr = stderr


def timed_run(files, specs, mode):
    with tempfile.TemporaryDirectory(prefix="batch-scale-") as out:
        kw = {"workers": 1} if mode == "serial" else {"workers": int(mode[4:]), "threads": 1}
        t0 = time.perf_counter()
        rows = batch.run(files, specs, out, charts=False, **kw)
        wall = time.perf_counter() - t0
    return wall, rows


def sha256_rate(files):
    """Bytes per second of file_sha256 over the inputs (read from the page cache: the best case)."""
    t0 = time.perf_counter()
    size = sum(os.path.getsize(f) for f in files)
    for f in files:
        batch.file_sha256(f)
    return size / (time.perf_counter() - t0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--materials", nargs="+", default=["../shared/data/rgl"])
    p.add_argument("--specs", nargs="+", default=bench.QUICK_SPECS)
    p.add_argument("--runs", nargs="+", default=["serial", "dask1", "dask2"])
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--noop", type=int, default=2000)
    p.add_argument("--project", type=int, metavar="M", help="materials of the projected database")
    p.add_argument("--cores", nargs="+", type=int, default=[8, 64, 512])
    args = p.parse_args()

    files = batch.material_files(args.materials)
    print(f"{len(files)} materials × {len(args.specs)} specs; {os.cpu_count()} CPUs; load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())} at start")
    rows = []
    runs = {mode: [] for mode in args.runs}
    loads = []
    for _ in range(args.repeat):
        for mode in args.runs:
            wall, rows = timed_run(files, args.specs, mode)
            ok = [r for r in rows if r["status"] == "ok"]
            task_wall = sum(r["load_seconds"] + r["build_seconds"] + r["measure_seconds"] + r["write_seconds"]
                            for r in ok)
            runs[mode].append((wall, task_wall, sum(r["cpu_seconds"] for r in ok)))
            loads.append(os.getloadavg()[0])
            print(f"  {mode}: {wall:.0f} s, load {loads[-1]:.1f}", flush=True)
            failed = [r for r in rows if r["status"] != "ok"]
            if failed:
                print(f"  {len(failed)} failed: {failed[0]['material']} {failed[0]['spec']}: {failed[0]['error']}")
    print(f"| run | wall s (median, range of {args.repeat}) | Σ task wall s | Σ task CPU s | speed-up |")
    print("|---|---|---|---|---|")
    first = statistics.median(w for w, _, _ in runs[args.runs[0]])
    for mode, got in runs.items():
        wall = statistics.median(w for w, _, _ in got)
        print(f"| {mode} | {wall:.0f} ({min(w for w, _, _ in got):.0f}–{max(w for w, _, _ in got):.0f}) | "
              f"{statistics.median(t for _, t, _ in got):.0f} | {statistics.median(c for _, _, c in got):.0f} | "
              f"{first / wall:.2f} |")
    print(f"load average after each run: {min(loads):.1f}–{max(loads):.1f}")

    print("\n| spec | load s | build s | measure s | write s | CPU s |")
    print("|---|---|---|---|---|---|")
    per_spec = {}
    for spec in args.specs:
        mine = [r for r in rows if r["spec"] == spec and r["status"] == "ok"]
        if not mine:
            continue
        per_spec[spec] = statistics.mean(r["cpu_seconds"] for r in mine)
        med = {k: statistics.median(r[k] for r in mine) for k in
               ("load_seconds", "build_seconds", "measure_seconds", "write_seconds", "cpu_seconds")}
        print(f"| `{spec}` | {med['load_seconds']:.3f} | {med['build_seconds']:.2f} | {med['measure_seconds']:.2f} | "
              f"{med['write_seconds']:.3f} | {med['cpu_seconds']:.2f} |")

    per_task, start = scheduler_overhead(args.noop)
    print(f"\nscheduler: {per_task * 1e3:.2f} ms per task ({args.noop} empty tasks, 2 workers); "
          f"LocalCluster start {start:.1f} s; load average {os.getloadavg()[0]:.1f}")

    if args.project:
        m = args.project
        rate = sha256_rate(files)
        input_bytes = statistics.mean(os.path.getsize(f) for f in files)
        n = m * len(per_spec)
        work = m * sum(per_spec.values())
        longest = max(per_spec.values())
        serial = start + m * input_bytes / rate
        print(f"\nprojection: {m} materials × {len(per_spec)} specs = {n} tasks, {work / 3600:.1f} CPU-hours "
              f"(mean CPU s per task of each spec, this run); longest task {longest:.0f} s; scheduler "
              f"{n * per_task:.0f} s; start + hashing ({rate / 1e6:.0f} MB/s) {serial:.0f} s")
        print("| cores | W / C + t_max | scheduler N·o | projected wall |")
        print("|---|---|---|---|")
        for c in args.cores:
            spread = work / c + longest
            wall = serial + max(spread, n * per_task)
            print(f"| {c} | {spread / 60:.1f} min | {n * per_task:.0f} s | {wall / 60:.1f} min |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
