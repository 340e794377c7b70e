"""brdfz against Mitsuba 3's `measured` plugin on one RGL-EPFL file, one thread each (issue 23's table):

    PYTHONPATH=build/python .venv/bin/python bench/vs_mitsuba.py FILE.bsdf [FILE...] [--spec SPEC] [--reps N]
        [--pairs N] [--cpp build/bench/rgl_batch] [--no-render]

Five ratios, in one run:
  1. brdfz's batch eval of the file (Brdf.eval) / measured's eval, the same pairs
  2. brdfz's batch sample with weights (Brdf.sample) / measured's sample, the same views and u
  3. the representation SPEC's batch eval / measured's eval on the file
  4. the representation's batch sample / measured's sample on the file
  5. the render time of a sphere (128², 64 spp, path depth 2, sun + sky) with the representation through
     brdfz.mitsuba.bsdf / the same scene with `measured` and the file (lower is better here)
Mitsuba runs in llvm_ad_rgb with Dr.Jit's thread count 1, each call evaluated (dr.eval) and waited for;
brdfz's batch calls run on the calling thread. Pairs: N (default 2^20) random directions uniform on the
upper hemisphere, rounded to float32 (Mitsuba's precision) for both. Every repetition runs every case in
turn; the figures are medians over the repetitions of this process's CPU time (the machine may be shared:
wall times are printed too), after one warm-up. The render scene is brdfz.examples.mitsuba_sphere's, with
`measured` rendered in Mitsuba's default (symbolic) mode and brdfz in whatever mode its bridge sets.
The SIMD widths used: brdfz.simd() and the vector width in Dr.Jit's generated LLVM IR. With --cpp, the
C++ program bench/rgl_batch.cpp times the same calls without Python (its own pairs, same distribution).
With several files, each is measured in turn and a last table lists the five ratios per file.
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import tempfile
import time

import numpy as np

# The ≤ 16 KB representation of bench/README.md (14,944 bytes); symmetry=none, as the RGL files are not
# reciprocal (their reciprocal mean is 1.5–9.7 % off on the size benchmark's four).
DEFAULT_SPEC = "svd:rank=8,space=cos,colour=shared,res=64x48x18,dwarp=0.9,fit=lsq,symmetry=none,dtype=f16"
TARGETS = ["≥ 1.0", "≥ 1.0", "≥ 1.5", "≥ 1.5", "≤ 1.2"]


def upper_hemisphere(rng, n):
    z = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    v = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    return v.astype(np.float32).astype(np.float64)


def timed(fn):
    """(CPU seconds, wall seconds) of fn()."""
    c0, w0 = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - c0, time.perf_counter() - w0


def drjit_lanes(dr) -> int:
    """The float lanes of Dr.Jit's LLVM kernels here, read from the IR of a small one."""
    import drjit.llvm as llvm

    fd, path = tempfile.mkstemp()
    saved = [os.dup(1), os.dup(2)]
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        dr.set_flag(dr.JitFlag.PrintIR, True)
        x = llvm.Float(1.0, 2.0, 3.0)
        dr.eval(x * 3.25 + 0.5)
    finally:
        dr.set_flag(dr.JitFlag.PrintIR, False)
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(fd)
    with open(path) as f:
        text = f.read()
    os.unlink(path)
    widths = re.findall(r"<(\d+) x float>", text)
    return int(widths[0]) if widths else 0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+", metavar="FILE", help="RGL-EPFL .bsdf files (isotropic RGB)")
    ap.add_argument("--spec", default=DEFAULT_SPEC, help="the representation (default: the ≤ 16 KB svd spec)")
    ap.add_argument("--reps", type=int, default=7, help="repetitions, at least 5 (default 7)")
    ap.add_argument("--pairs", type=int, default=1 << 20, help="direction pairs per call (default 2^20)")
    ap.add_argument("--render-reps", type=int, default=5, help="render repetitions, at least 5 (default 5)")
    ap.add_argument("--no-render", action="store_true", help="leave out ratio 5")
    ap.add_argument("--cpp", default="", help="also run this build of bench/rgl_batch.cpp on the file and spec")
    args = ap.parse_args()
    if args.reps < 5 or args.render_reps < 5:
        ap.error("--reps and --render-reps must be at least 5 (medians of five runs or more)")
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    summary = [(f, measure(f, args)) for f in args.files]
    if len(summary) > 1:
        print("\nratios per file (CPU time):")
        print("  " + " | ".join(["file", "RGL eval", "RGL sample", "repr eval", "repr sample", "render"]))
        for f, ratios in summary:
            print("  " + " | ".join([os.path.basename(f)] + [f"{r:.2f}" for r in ratios]))


def measure(file: str, args) -> list:
    """Measures one file, prints its figures and returns its ratios (render last, when measured)."""
    import drjit as dr
    import mitsuba as mi

    dr.set_thread_count(1)
    import brdfz
    import brdfz.mitsuba
    from brdfz.examples.mitsuba_sphere import scene

    load = os.getloadavg()
    rgl = brdfz.load(file)
    compressed = brdfz.compress(rgl, args.spec, report=True)
    build_s = compressed.build_seconds
    repr_ = compressed.brdf
    measured = mi.load_dict({"type": "measured", "filename": str(file)})

    n = args.pairs
    rng = np.random.default_rng(20261201)
    wi, wo = upper_hemisphere(rng, n), upper_hemisphere(rng, n)
    u = rng.uniform(0.0, 1.0, (n, 2)).astype(np.float32).astype(np.float64)
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))  # Mitsuba's si.wi: the file's incident
    si_view = dr.zeros(mi.SurfaceInteraction3f, n)
    si_view.wi = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))
    m_wo = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))
    sample1 = mi.Float(np.zeros(n, dtype=np.float32))
    sample2 = mi.Point2f(np.ascontiguousarray(u.T, dtype=np.float32))

    def m_eval():
        v = measured.eval(ctx, si, m_wo)
        dr.eval(v)
        dr.sync_thread()

    def m_sample():
        bs, w = measured.sample(ctx, si_view, sample1, sample2)
        dr.eval(bs, w)
        dr.sync_thread()

    cases = {
        "measured eval": m_eval,
        "measured sample": m_sample,
        "rgl eval": lambda: rgl.eval(wi, wo),
        "rgl sample": lambda: rgl.sample(wo, u),
        "repr eval": lambda: repr_.eval(wi, wo),
        "repr sample": lambda: repr_.sample(wo, u),
    }
    cpu = {k: [] for k in cases}
    wall = {k: [] for k in cases}
    for fn in cases.values():  # warm-up: Dr.Jit compiles its kernels, brdfz builds its samplers
        fn()
    for _ in range(args.reps):
        for name, fn in cases.items():
            c, w = timed(fn)
            cpu[name].append(c)
            wall[name].append(w)
    rate = {k: n / statistics.median(v) / 1e6 for k, v in cpu.items()}
    wall_rate = {k: n / statistics.median(v) / 1e6 for k, v in wall.items()}

    render = None
    if not args.no_render:
        symbolic = {f: dr.flag(f) for f in (dr.JitFlag.SymbolicLoops, dr.JitFlag.SymbolicCalls)}

        def render_measured():
            for f, on in symbolic.items():
                dr.set_flag(f, on)
            img = mi.render(scene({"type": "measured", "filename": str(file)}, 128, 64))
            dr.eval(img)
            dr.sync_thread()

        def render_brdfz():
            img = mi.render(scene(brdfz.mitsuba.bsdf(repr_), 128, 64))
            dr.eval(img)
            dr.sync_thread()

        times = {"measured": [], "brdfz": []}
        walls = {"measured": [], "brdfz": []}
        render_measured()
        render_brdfz()
        for _ in range(args.render_reps):
            for name, fn in (("measured", render_measured), ("brdfz", render_brdfz)):
                c, w = timed(fn)
                times[name].append(c)
                walls[name].append(w)
        for f, on in symbolic.items():
            dr.set_flag(f, on)
        render = {k: statistics.median(v) for k, v in times.items()}
        render_wall = {k: statistics.median(v) for k, v in walls.items()}

    print(f"file: {file}")
    print(f"representation: {args.spec} ({repr_.nbytes:,} B, built in {build_s:.1f} s): {repr_.describe()}")
    print(f"SIMD: brdfz {brdfz.simd()} (brdfz.simd()); Mitsuba llvm_ad_rgb, {drjit_lanes(dr)} float lanes "
          f"(Dr.Jit's LLVM IR); one thread each")
    print(f"pairs: {n:,}; repetitions: {args.reps} (render {args.render_reps}); load average at start "
          f"{load[0]:.1f}, at end {os.getloadavg()[0]:.1f}")
    print("medians of CPU time (wall time in brackets), M per second:")
    for k in cases:
        print(f"  {k:16s} {rate[k]:8.2f}  ({wall_rate[k]:.2f})")
    rows = [
        ("brdfz RGL batch eval / measured eval", rate["rgl eval"] / rate["measured eval"]),
        ("brdfz RGL batch sample / measured sample", rate["rgl sample"] / rate["measured sample"]),
        ("representation batch eval / measured eval", rate["repr eval"] / rate["measured eval"]),
        ("representation batch sample / measured sample", rate["repr sample"] / rate["measured sample"]),
    ]
    if render:
        print(f"  render 128², 64 spp: measured {render['measured']:.2f} s ({render_wall['measured']:.2f}), "
              f"brdfz {render['brdfz']:.2f} s ({render_wall['brdfz']:.2f})")
        rows.append(("render time, representation through brdfz.mitsuba / measured", render["brdfz"] / render["measured"]))
    print("ratios (CPU time), target:")
    for (what, ratio), target in zip(rows, TARGETS):
        print(f"  {what:62s} {ratio:6.2f}   {target}")

    if args.cpp:
        run = subprocess.run([args.cpp, str(file), "--spec", args.spec, "--reps", str(args.reps)],
                             capture_output=True, text=True, check=True)
        print(f"C++ ({args.cpp}):")
        for line in run.stdout.splitlines():
            print("  " + line)
    return [ratio for _, ratio in rows]


if __name__ == "__main__":
    main()
