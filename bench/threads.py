"""Threaded evaluation from Python: does `Brdf.eval` (and `sample`) scale with Python threads?

    PYTHONPATH=build/python .venv/bin/python bench/threads.py [FILE] [--pairs N] [--reps R]

The same total work (N direction pairs) is split over 1, 2, ... os.cpu_count() Python threads, each
calling `eval` (then `sample`) on its own slice; the GIL is released inside, so on idle cores the wall
time should fall with the thread count. Prints medians over interleaved repetitions, throughput and
the speedup against one thread measured in the same run (issue #7). FILE defaults to the generated
gold-metallic-paint MERL table.
"""
import argparse
import os
import statistics
import threading
import time

import numpy as np

import brdfz


def random_dirs(rng, n):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def run_threads(work, slices):
    """Wall time of running work(slice) for every slice, one Python thread each."""
    threads = [threading.Thread(target=work, args=(s,)) for s in slices]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", nargs="?", default="build/merl-tables/gold-metallic-paint.binary")
    ap.add_argument("--pairs", type=int, default=4_000_000)
    ap.add_argument("--reps", type=int, default=7)
    args = ap.parse_args()

    brdf = brdfz.load(args.file)
    rng = np.random.default_rng(1)
    wi, wo = random_dirs(rng, args.pairs), random_dirs(rng, args.pairs)
    u = rng.random((args.pairs, 2))
    counts = list(range(1, (os.cpu_count() or 1) + 1))
    ops = {
        "eval": lambda s: brdf.eval(wi[s], wo[s]),
        "sample": lambda s: brdf.sample(wo[s], u[s]),
    }
    print(f"{args.file}: {args.pairs:,} pairs, {args.reps} interleaved reps, load {os.getloadavg()[0]:.2f}")
    times = {(op, n): [] for op in ops for n in counts}
    for _ in range(args.reps):
        for op, work in ops.items():
            for n in counts:
                bounds = np.linspace(0, args.pairs, n + 1).astype(int)
                slices = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
                times[(op, n)].append(run_threads(work, slices))
    print("| op | threads | median wall | M per s | speedup vs 1 thread |")
    print("|---|---|---|---|---|")
    for op in ops:
        base = statistics.median(times[(op, 1)])
        for n in counts:
            t = statistics.median(times[(op, n)])
            print(f"| {op} | {n} | {t * 1e3:.1f} ms | {args.pairs / t / 1e6:.2f} | {base / t:.2f}x |")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
