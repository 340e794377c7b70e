"""Renders a sphere with a measured RGL-EPFL material through Mitsuba 3's own `measured` plugin and
through brdfz (the .bsdf file loaded by brdfz.load, or a representation compressed from it), at the
same sample count and sampler seed, and reports the PSNR of the brdfz images against Mitsuba's.

    python -m brdfz.examples.mitsuba_sphere ../shared/data/rgl/paper_white_rgb.bsdf [--res 64] [--spp 16]
        [--compress tabular:res=90x90x180] [--runs 5 --threads 1]

brdfz is rendered with both settings of the bridge's `incident` (brdfz.mitsuba): "camera" (the
default) reads the file's incident direction at Mitsuba's si.wi as `measured` does (like for like:
only rounding differs), "light" at the light (differs by the data's non-reciprocity). A compressed
representation renders through the native bridge (Dr.Jit code in Mitsuba's kernels), the file itself
through the wavefront bridge (brdfz.mitsuba).

Scene: a unit sphere seen from 4 units away, lit by a directional light and a constant environment,
path traced with one bounce (direct light: emitter samples use eval and pdf, BSDF samples use
sample), so every part of the bridge contributes. PSNR = 10·log10(peak² / MSE) over all pixels and
channels, peak the reference image's maximum. With --runs R each scene is rendered once to compile
its kernels and then R times more, the scenes taking turns, and the median time is reported
(--threads: Dr.Jit's thread count).
"""
from __future__ import annotations

import argparse
import statistics
import time

import drjit as dr
import mitsuba as mi
import numpy as np

import brdfz
import brdfz.mitsuba


def scene(material, res: int, spp: int, integrator: str = "path") -> "mi.Scene":
    """A sphere lit by a sun and a sky; `integrator` "prb" makes it differentiable (inverse_render)."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": integrator, "max_depth": 2},
        "sensor": {
            "type": "perspective",
            "fov": 35,
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp, "seed": 7},
        },
        "sphere": {"type": "sphere", "bsdf": material},
        "sun": {"type": "directional", "direction": [-1.0, -0.6, -1.0], "irradiance": {"type": "rgb", "value": 3.0}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 0.3}},
    })


def render(material, res: int, spp: int) -> np.ndarray:
    return np.array(mi.render(scene(material, res, spp)), dtype=np.float64)


def psnr(reference: np.ndarray, image: np.ndarray) -> float:
    mse = float(np.mean((reference - image) ** 2))
    peak = float(reference.max())
    return float("inf") if mse == 0 else 10.0 * np.log10(peak * peak / mse)


def _timed(sc) -> tuple:
    t0 = time.perf_counter()
    image = np.array(mi.render(sc), dtype=np.float64)
    return image, time.perf_counter() - t0


def compare(path, res: int = 64, spp: int = 16, spec: str = "", incidents=("camera", "light"), runs: int = 1) -> dict:
    """Renders `path` through `measured`, then through brdfz (compressed with `spec` when given) for
    each bridge setting in `incidents`. Returns the reference image and its render time, the brdfz
    Brdf's description, and per setting the image, its PSNR and its render time: of the first render
    (compilation included), or with runs > 1 the median of `runs` more, the scenes taking turns."""
    if not mi.variant():
        mi.set_variant("llvm_ad_rgb")
    # `measured` first: a wavefront brdfz BSDF switches the process to wavefront mode when built.
    scenes = {"reference": scene({"type": "measured", "filename": str(path)}, res, spp)}
    images, seconds = {}, {}
    images["reference"], seconds["reference"] = _timed(scenes["reference"])
    brdf = brdfz.load(path)
    if spec:
        brdf = brdfz.compress(brdf, spec)
    for incident in incidents:
        scenes[incident] = scene(brdfz.mitsuba.bsdf(brdf, incident), res, spp)
        images[incident], seconds[incident] = _timed(scenes[incident])
    if runs > 1:
        times = {k: [] for k in scenes}
        for _ in range(runs):
            for k, sc in scenes.items():
                images[k], t = _timed(sc)
                times[k].append(t)
        seconds = {k: statistics.median(v) for k, v in times.items()}
    out = {"reference": images["reference"], "reference_seconds": seconds["reference"], "brdf": brdf.describe()}
    for incident in incidents:
        out[incident] = {"image": images[incident], "psnr": psnr(images["reference"], images[incident]),
                         "seconds": seconds[incident]}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file", help="an RGL-EPFL .bsdf file (RGB)")
    parser.add_argument("--res", type=int, default=64, help="image width and height")
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel (every render)")
    parser.add_argument("--compress", default="", help="render this representation of the file, e.g. tabular:res=45x45x90")
    parser.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    parser.add_argument("--save", default="", help="write the images side by side (measured, camera, light) to this .exr")
    parser.add_argument("--runs", type=int, default=1, help="time the median of this many renders after a warm-up")
    parser.add_argument("--threads", type=int, default=0, help="Dr.Jit's thread count (0: its default)")
    args = parser.parse_args()
    mi.set_variant(args.variant)
    if args.threads:
        dr.set_thread_count(args.threads)
    r = compare(args.file, args.res, args.spp, args.compress, runs=args.runs)
    print(f"{args.file}: {r['brdf']}")
    print(f"  {args.res}x{args.res}, {args.spp} spp; measured: {r['reference_seconds']:.3f} s")
    for incident in ("camera", "light"):
        print(f"  brdfz, incident={incident}: {r[incident]['seconds']:.3f} s "
              f"({r[incident]['seconds'] / r['reference_seconds']:.2f}x measured), PSNR {r[incident]['psnr']:.2f} dB")
    if args.save:
        images = [r["reference"], r["camera"]["image"], r["light"]["image"]]
        mi.Bitmap(np.concatenate(images, axis=1).astype(np.float32)).write(args.save)


if __name__ == "__main__":
    main()
