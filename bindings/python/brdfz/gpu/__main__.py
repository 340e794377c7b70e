"""python -m brdfz.gpu check FILE [--backend wgpu|gl] [--pairs N]: the shaders against the C++
library on a .brdfzrt material (brdfz export IN -o FILE); prints the worst relative errors, exit status 1
above tolerance, 2 when the backend cannot start."""

import argparse
import json
import sys

from .backend import BackendUnavailable
from .check import BACKENDS, TOLERANCE, check
from .slang import SlangError


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m brdfz.gpu")
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="eval, pdf and sample on the GPU against the C++ library")
    c.add_argument("file", help="a runtime layout (.brdfzrt)")
    c.add_argument("--backend", default="wgpu", choices=BACKENDS)
    c.add_argument("--pairs", type=int, default=100_000)
    c.add_argument("--tolerance", type=float, default=TOLERANCE)
    c.add_argument("--json", action="store_true", help="the whole report as JSON")
    args = parser.parse_args(argv)
    try:
        r = check(args.file, gpu=args.backend, n=args.pairs, tol=args.tolerance)
    except (BackendUnavailable, SlangError, ValueError) as e:
        print(f"brdfz.gpu: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(r, indent=2))
    else:
        s = r["sample"]
        print(f"{args.file}: {r['backend']}, {r['pairs']} pairs")
        print(f"  eval   worst relative error {r['eval']['worst']:.3g} (99th percentile {r['eval']['p99']:.3g}; "
              f"{r['eval']['within_rounding']} matched within float rounding of their directions)")
        print(f"  pdf    worst relative error {r['pdf']['worst']:.3g} (99th percentile {r['pdf']['p99']:.3g}; "
              f"{r['pdf']['within_rounding']} matched within float rounding of their directions)")
        print(f"  sample {s['drawn']} drawn ({s['failed']} failed; library {s['failed_library']}): pdf against its own "
              f"pdf {s['pdf_vs_own_pdf']:.3g}, weight against its own eval {s['weight_vs_own_eval']:.3g}, "
              f"pdf against the library {s['pdf_vs_library']:.3g} ({s['within_rounding']} within float rounding); "
              f"{100 * s['same_draw']:.3f}% the library's draw")
        print(f"  {'ok' if r['ok'] else 'FAILED'}: worst {r['worst']:.3g}, tolerance {args.tolerance:g}")
    return 0 if r["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
