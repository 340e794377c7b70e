"""python -m brdfz.gpu check FILE [--backend wgpu|gl|webgl] [--pairs N]: the shaders against the C++
library on a .brdfzrt material (brdfz export IN -o FILE); prints the worst relative errors, exit status 1
above tolerance, 2 when the backend cannot start.

python -m brdfz.gpu export IN -o DIR --target T [--repr SPEC] (also `brdfz export ... --target T`): the
material's buffers, the shader module, brdfz.json and INTEGRATION.md for a GPU renderer (brdfz.gpu.export);
exit status 2 on bad input."""

import argparse
import json
import sys

from .backend import BackendUnavailable
from .check import BACKENDS, TOLERANCE, check
from .export import EXPORT_TARGETS, export
from .slang import SlangError


def _export(args):
    import brdfz

    try:
        d = export(args.input, args.output, args.target, repr=args.repr, reference=args.reference,
                   error_pairs=args.error_pairs, threads=args.threads, progress=True)
    except (brdfz.FormatError, brdfz.UnsupportedError, SlangError, ValueError, OSError) as e:
        print(f"brdfz export: {e}", file=sys.stderr)
        return 2
    error = d["error"]
    measured = (f"cos_rmse_rel {error['cos_rmse_rel']:.4g} over {error['over']}" if error else "error not measured "
                "(no reference: give --reference, or --repr to build from IN)")
    print(f"wrote {args.output}: {args.target}, {d['representation']}, {d['bytes']} B, {measured}")
    for f in d["files"]:
        print(f"  {f}")
    return 0


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m brdfz.gpu")
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="eval, pdf and sample on the GPU against the C++ library")
    c.add_argument("file", help="a runtime layout (.brdfzrt)")
    c.add_argument("--backend", default="wgpu", choices=BACKENDS)
    c.add_argument("--pairs", type=int, default=100_000)
    c.add_argument("--tolerance", type=float, default=TOLERANCE)
    c.add_argument("--json", action="store_true", help="the whole report as JSON")
    e = sub.add_parser("export", help="a material's buffers, shader module, descriptor and notes for a GPU renderer")
    e.add_argument("input", metavar="IN", help="a BRDF file brdfz reads")
    e.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write (created)")
    e.add_argument("--target", required=True, choices=EXPORT_TARGETS)
    e.add_argument("--repr", help="build this representation first (brdfz representations lists them)")
    e.add_argument("--reference", help="measure the error against this file (default: IN when --repr builds from it)")
    e.add_argument("--error-pairs", type=int, default=1 << 16, help="direction pairs the error is measured on")
    e.add_argument("--threads", type=int, default=0)
    args = parser.parse_args(argv)
    if args.command == "export":
        return _export(args)
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
