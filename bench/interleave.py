#!/usr/bin/env python3
"""Two builds of one benchmark, run alternately (A, B, A, B, ...), compared case by case.

    bench/interleave.py --rounds 5 --a "OLD/bench/rgl_batch FILE" --b "NEW/bench/rgl_batch FILE"

Each command prints a table whose rows are `CASE  numbers... | CPU-ms ...` (rgl_batch, factored_eval),
`  file | r1 | r2 ...` ratio rows (vs_mitsuba.py's "ratios per file"), `CASE ... median T ms` rows
(tabular_eval, compact_eval), sample's `sample() (...), WHERE: R M samples/s ..., R' M/s in blocks`
lines (taken as times per sample and per draw) or CSV under a header line (runtime_bench: a row's text
cells name its case, its columns ending in _ns, _us or _ms are its times). For every case and column the ratio A / B of each round
is taken; the report is the median of those ratios and their range (for times, > 1: B faster; for
vs_mitsuba's brdfz ÷ measured ratios, < 1: B faster). Commands run through the shell, so an environment
assignment (PYTHONPATH=...) may lead them.
"""
import argparse
import csv
import re
import statistics
import subprocess
import sys

NUMBER = r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"


def figures(text: str) -> dict:
    """{(case, column): value} from one run's output."""
    out = {}
    header = None
    for line in text.splitlines():
        if re.fullmatch(r"[a-z_][a-z0-9_]*(,[a-z_][a-z0-9_]*)+", line.strip()):
            header = line.strip().split(",")
            continue
        if header:
            cells = next(csv.reader([line]), [])
            if len(cells) == len(header):  # a CSV row: its text cells name the case
                case = " ".join(c for c in cells if not re.fullmatch(NUMBER, c))
                for name, c in zip(header, cells):
                    if name.endswith(("_ns", "_us", "_ms")) and re.fullmatch(NUMBER, c):
                        out[(case, name)] = float(c)
                continue
        median = re.match(rf"\s*(\S.*?)\s+median\s+({NUMBER}) ms", line)
        if median:  # CASE ... median T ms
            out[(re.sub(r"\s+", " ", median.group(1)), "ms")] = float(median.group(2))
            continue
        sampled = re.match(rf"\s*sample\(\) \(.*?\), (.*?): ({NUMBER}) M samples/s", line)
        if sampled:  # sample's speed lines, as ns per sample and per draw
            out[(f"sample(), {sampled.group(1)}", "ns")] = 1e3 / float(sampled.group(2))
            blocks = re.search(rf"({NUMBER}) M/s in blocks", line)
            if blocks:
                out[(f"draw in blocks, {sampled.group(1)}", "ns")] = 1e3 / float(blocks.group(1))
            continue
        if "|" not in line:
            continue
        left, _, right = line.partition("|")
        cells = [c.strip() for c in line.split("|")]
        if all(re.fullmatch(NUMBER, c) for c in cells[1:]) and len(cells) > 2 and not re.fullmatch(NUMBER, cells[0]):
            for k, c in enumerate(cells[1:]):  # a ratio row: name | r1 | r2 ...
                out[(cells[0], f"col{k + 1}")] = float(c)
            continue
        m = re.match(rf"\s*(\S.*?)\s+({NUMBER})\s", left)
        first_right = re.match(rf"\s*({NUMBER})", right)
        if m and first_right:  # a timing row: CASE wall ... | CPU ms ...
            out[(m.group(1), "CPU ms")] = float(first_right.group(1))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--a", required=True, help="command of build A (the reference)")
    ap.add_argument("--b", required=True, help="command of build B")
    ap.add_argument("--rounds", type=int, default=5, help="A/B pairs, at least 3 (default 5)")
    args = ap.parse_args()
    if args.rounds < 3:
        ap.error("--rounds must be at least 3")
    ratios: dict = {}
    for r in range(args.rounds):
        runs = {}
        for name, cmd in (("A", args.a), ("B", args.b)):
            print(f"round {r + 1}/{args.rounds}: {name}", file=sys.stderr, flush=True)
            done = subprocess.run(cmd, shell=True, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(f"interleave.py: {name} failed ({done.returncode}): {done.stderr.strip()[-500:]}")
            runs[name] = figures(done.stdout)
        for key in runs["A"].keys() & runs["B"].keys():
            if runs["B"][key] != 0:
                ratios.setdefault(key, []).append(runs["A"][key] / runs["B"][key])
    if not ratios:
        sys.exit("interleave.py: no case appeared in both outputs")
    print(f"A: {args.a}\nB: {args.b}\nrounds: {args.rounds}; A / B per round, median (range)")
    width = max(7, *(len(column) for _, column in ratios))
    for (case, column), v in sorted(ratios.items()):
        print(f"  {case[:60]:60s} {column:{width}s} {statistics.median(v):6.3f} ({min(v):.3f}-{max(v):.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
