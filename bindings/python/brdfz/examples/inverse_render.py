"""Inverse rendering through the native Mitsuba bridge: a representation's parameters (a table's
entries, factors, PCA coefficients, lobe parameters: whatever mi.traverse lists for the BSDF) are
perturbed, then recovered from a reference render by gradient descent on the image difference.

    python -m brdfz.examples.inverse_render [FILE [--spec SPEC]] [--perturb 0.3] [--noise 0]
        [--iterations 40] [--res 32] [--spp 8] [--lr 0.02]

Without FILE the material is a built-in lambert+ggx model. Each differentiable array p is perturbed,
p·exp(perturb + noise·N(0, 1)) entry by entry (fixed seed: a miscalibrated representation, by default
35 % too high everywhere), and then optimised as p_start·exp(z) with Adam on z, one unknown per entry
(a step size in relative terms, whatever the entries' scale), the loss the mean squared difference
to the reference image. One view constrains only the entries it sees, so a table's unseen entries
keep their perturbation while the image converges. Renders use the `prb` integrator (path depth 2: emitter and BSDF sampling) with
one sample seed throughout, so the loss can fall to rounding once the parameters are back. Prints the
loss per iteration and the parameters' RMS log-ratio to the truth, before and after.
"""
from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import drjit as dr
import mitsuba as mi
import numpy as np

import brdfz
import brdfz.mitsuba

GLOSSY = {"lambert.rho_r": 0.2, "lambert.rho_g": 0.3, "lambert.rho_b": 0.4, "ggx.ks_r": 1.0, "ggx.ks_g": 0.8,
          "ggx.ks_b": 0.6, "ggx.alpha": 0.15, "ggx.f0": 0.04}


def builtin() -> brdfz.Brdf:
    """The default material: lambert+ggx, loaded from a model file as any analytic model."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "glossy.json")
        with open(path, "w") as f:
            json.dump({"format": "brdfz-analytic", "version": 1, "model": "lambert+ggx", "parameters": GLOSSY}, f)
        return brdfz.load(path)


def scene(material, res: int, spp: int) -> "mi.Scene":
    """mitsuba_sphere's scene (a sphere, sun and sky) with the differentiable path tracer."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {
            "type": "perspective",
            "fov": 35,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sphere": {"type": "sphere", "bsdf": material},
        "sun": {"type": "directional", "direction": [-1.0, -0.6, -1.0], "irradiance": {"type": "rgb", "value": 3.0}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 0.3}},
    })


def _log_ratio(a, b) -> float:
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    used = (x != 0) & (y != 0) & np.isfinite(x) & np.isfinite(y)
    return float(np.sqrt(np.mean(np.log(np.abs(x[used] / y[used])) ** 2))) if used.any() else 0.0


def recover(brdf: brdfz.Brdf, *, perturb: float = 0.3, noise: float = 0.0, iterations: int = 40, res: int = 32,
            spp: int = 8, lr: float = 0.02, seed: int = 1, log=None) -> dict:
    """Perturbs `brdf`'s differentiable arrays and recovers them from a reference render. Returns the
    losses per iteration and the parameters' RMS log-ratio to the truth before and after."""
    sc = scene(brdfz.mitsuba.bsdf(brdf, native=True), res, spp)
    params = mi.traverse(sc)
    keys = [k for k in params.keys() if k.startswith("sphere.bsdf.")]
    if not keys:
        raise ValueError(f"{brdf.describe()}: no differentiable parameters")
    reference = mi.render(sc, seed=0)
    rng = np.random.default_rng(seed)
    truth, start = {}, {}
    for k in keys:
        kind = type(params[k])
        truth[k] = np.array(params[k])
        start[k] = kind(truth[k] * np.exp(perturb + noise * rng.standard_normal(truth[k].shape)))
    opt = mi.ad.Adam(lr=lr)
    for k in keys:
        opt[k] = dr.zeros(type(params[k]), dr.width(params[k]))

    def apply() -> None:
        for k in keys:
            params[k] = start[k] * dr.exp(opt[k])
        params.update()

    before = max(_log_ratio(start[k], truth[k]) for k in keys)
    losses = []
    for it in range(iterations):
        t0 = time.perf_counter()
        apply()
        image = mi.render(sc, params, seed=0)
        loss = dr.mean(dr.square(image - reference), axis=None)
        dr.backward(loss)
        opt.step()
        losses.append(float(np.asarray(loss).reshape(-1)[0]))
        if log:
            log(f"  {it:3d}  loss {losses[-1]:.4e}  ({time.perf_counter() - t0:.2f} s)")
    apply()
    after = max(_log_ratio(params[k], truth[k]) for k in keys)
    return {"keys": keys, "losses": losses, "log_ratio_before": before, "log_ratio_after": after}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file", nargs="?", help="a file brdfz.load reads (default: a built-in lambert+ggx model)")
    parser.add_argument("--spec", default="", help="recover this representation of the file, e.g. svd:rank=2,res=16x16x32")
    parser.add_argument("--perturb", type=float, default=0.3, help="every entry scaled by exp(PERTURB)")
    parser.add_argument("--noise", type=float, default=0.0, help="and by exp(NOISE·N(0, 1)), entry by entry")
    parser.add_argument("--iterations", type=int, default=40)
    parser.add_argument("--res", type=int, default=32, help="image width and height")
    parser.add_argument("--spp", type=int, default=8)
    parser.add_argument("--lr", type=float, default=0.02, help="Adam's step in log space")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="a differentiable RGB variant")
    args = parser.parse_args()
    mi.set_variant(args.variant)
    brdf = brdfz.load(args.file) if args.file else builtin()
    if args.spec:
        brdf = brdfz.compress(brdf, args.spec)
    print(brdf.describe())
    r = recover(brdf, perturb=args.perturb, noise=args.noise, iterations=args.iterations, res=args.res, spp=args.spp,
                lr=args.lr, log=print)
    first, last = r["losses"][0], r["losses"][-1]
    print(f"parameters {', '.join(r['keys'])}: loss {first:.4e} -> {last:.4e} ({first / last:.1f}x lower); "
          f"RMS log-ratio to the truth {r['log_ratio_before']:.3f} -> {r['log_ratio_after']:.3f}")


if __name__ == "__main__":
    main()
