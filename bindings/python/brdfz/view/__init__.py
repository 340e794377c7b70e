"""A local web page to look at materials and their compact representations, in the spirit of BRDF
Explorer:

    python -m brdfz.view FILE... [--compare SPEC...] [--port N] [--html OUT] [--size 256] [--env-samples 64]
        [--passes 16]

Each FILE is a material brdfz.load reads; each --compare SPEC a representation of the first FILE
(brdfz.compress's specs). Python computes every view's values here with the library's eval (the
sampling of brdfz.plot), the page draws them on 2D canvases: polar plot, 3D lobe, θh × θd image and
albedo curve, two materials side by side with their relative error (masked where the first's incident
elevation is beyond its measured_theta_max). The lit sphere is rendered in the browser by the GPU
shaders (bindings/gpu/shaders/examples/sphere.slang translated to WGSL, run with WebGPU) on each
material's runtime layout, the light moved with the mouse. It keeps drawing after the first image:
pass p draws the sky anew (seed 1 + p) and the spheres and their error show the mean of the passes so
far, so that the sky's sampling noise falls as 1/√passes (the light moved starts again). A FILE whose
layout would exceed F16_ABOVE bytes (a measured table) is drawn from its float16 table on the same grid.

The page is one self-contained HTML file (data, scripts and shaders inline, nothing fetched), served
on 127.0.0.1 by the standard library's http.server, or written to --html OUT to open from disk. The
runtime layouts travel gzip-compressed (the browser's DecompressionStream unpacks them).
window.brdfzView exposes what the page drew, for tests.
"""
from __future__ import annotations

import argparse
import base64
import gzip
import http.server
import json
import math
import os
import pathlib
import sys
import tempfile
from typing import List, Optional, Sequence

import numpy as np

import brdfz
from brdfz import plot, report
from brdfz.gpu import Layout, slang

HERE = pathlib.Path(__file__).parent
SPHERE = slang.SHADERS / "examples" / "sphere.slang"
THETA_I = (0.0, 30.0, 60.0)     # incidences of the polar plot and the lobe (degrees)
# Rounded to float32 as the page holds them, so that its points are those evaluated.
POLAR_ANGLES = np.linspace(-89.5, 89.5, 181).astype(np.float32).astype(float)
LOBE_RES = (24, 48)             # elevations × azimuths of the lobe's outgoing directions
SLICE_RES = 64                  # θh × θd bins
SLICE_PHI_D = 90.0
ALBEDO_THETA = np.arange(0.0, 90.0)
# A layout above this many bytes that is a float32 table (a measured FILE's, 17.5 MB at 90×90×180) is
# drawn from its float16 table: values within 2^-11 relative, half the bytes, a third once compressed.
F16_ABOVE = 4 << 20


def _f32(a) -> str:
    """Base64 of little-endian float32: compact in the page, and decoded without parsing numbers."""
    return base64.b64encode(np.ascontiguousarray(a, "<f4").tobytes()).decode()


def _packed(data: bytes) -> str:
    """Base64 of gzip of the bytes at even offsets, then those at odd ones: a float16's high bytes
    (sign, exponent) compress apart from its noisy low ones (a third smaller than gzip alone on a
    measured table). view.js's unpack reverses it."""
    a = np.frombuffer(data, np.uint8)
    if a.size % 2:
        raise ValueError(f"a runtime layout of {a.size} bytes (layouts are multiples of 64)")
    return base64.b64encode(gzip.compress(np.concatenate([a[0::2], a[1::2]]).tobytes(), 6, mtime=0)).decode()


def sphere_layout(brdf: brdfz.Brdf, path) -> dict:
    """Writes the runtime layout the page's sphere renders for `brdf` to `path`: brdfz.export's, or, when
    that is a float32 table above F16_ABOVE bytes, the same table in float16: a table's on its own grid,
    another source's (RGL, scattered) on the exporter's (90×90×180, φd kept whole unless reciprocal).
    Returns brdfz.export's dict (path, bytes, describe)."""
    info = brdfz.export(brdf, path)
    kind = (brdf.parts() or {}).get("kind")
    if info["bytes"] > F16_ABOVE and kind in ("tabular", None):
        spec = "tabular:dtype=f16" if kind else "tabular:res=90x90x180,dtype=f16"
        if kind is None and not brdfz.is_reciprocal(brdf):
            spec = brdfz.keep_phi_d_whole([spec])[0]
        info = brdfz.export(brdf, path, repr=spec)
    return info


def _mean(f: np.ndarray) -> np.ndarray:
    return f.mean(axis=-1)


def lobe_directions() -> np.ndarray:
    """Outgoing directions (elevations, azimuths + 1, 3) of the lobe's mesh, the last azimuth closing it."""
    el = np.radians((np.arange(LOBE_RES[0]) + 0.5) * 90 / LOBE_RES[0])
    az = np.radians(np.arange(LOBE_RES[1] + 1) * 360 / LOBE_RES[1])
    return brdfz.directions(el[:, None], az[None, :])


def slice_directions():
    """(wi, wo) on the θh (columns) × θd (rows) bin centres at φd = SLICE_PHI_D."""
    axis = np.radians((np.arange(SLICE_RES) + 0.5) * 90 / SLICE_RES)
    return brdfz.from_half_diff(axis[None, :], axis[:, None], math.radians(SLICE_PHI_D))


def views(brdf: brdfz.Brdf) -> dict:
    """The values the page plots for one material: polar (θi, θo, rgb), lobe (θi, el, az; mean),
    slice (θd, θh; mean), albedo (θo, rgb)."""
    wo = plot.plane_directions(0.0, 0.0, POLAR_ANGLES)[1]
    wi = brdfz.directions(np.radians(THETA_I), 0.0)
    polar = brdf.eval(wi[:, None, :], wo[None, :, :])
    lobe = _mean(brdf.eval(wi[:, None, None, :], lobe_directions()[None]))
    slice_ = _mean(brdf.eval(*slice_directions()))
    albedo = brdfz.albedo(brdf, np.radians(ALBEDO_THETA))
    return {"polar": _f32(polar), "lobe": _f32(lobe), "slice": _f32(slice_), "albedo": _f32(albedo)}


def _material(label: str, brdf: brdfz.Brdf, rt: dict, source: str, nbytes: int) -> dict:
    layout = Layout(rt["path"])
    return {"label": label, "describe": brdf.describe(), "source": source, "bytes": nbytes,
            "theta_max": float(brdf.measured_theta_max), "views": views(brdf), "sphere_describe": rt["describe"],
            "layout": _packed(layout.data), "desc": base64.b64encode(layout.desc.tobytes()).decode(),
            "layout_bytes": len(layout.data)}


def build(files: Sequence[str], compare: Sequence[str] = (), *, size: int = 256, env_samples: int = 64,
          passes: int = 16, progress: bool = True) -> dict:
    """The page's data: every material's views and runtime layout, the sphere's WGSL and parameters.
    The spheres render each material's sphere_layout. B starts as the first SPEC, else the second FILE."""
    # Every file is read, and the representations built, before the other long steps: bad input fails
    # early (a malformed first spec before any progress line).
    loaded = [brdfz.load(f) for f in files]
    bar = report.Bar("views", len(files) + 2 * len(compare) + 1) if progress else None

    def step(what):
        if bar is not None:
            bar.step(what)

    built = []
    for spec in compare:
        built.append(brdfz.compress(loaded[0], spec))
        step(f"built {spec}")
    # Without the Slang compiler the page still plots; it says why the sphere is missing.
    try:
        code, missing = slang.compile_entry(os.fspath(SPHERE), "sphere_render", "wgsl",
                                            include=(os.fspath(slang.SHADERS),)).decode(), None
    except slang.SlangError as e:
        code, missing = None, str(e)
        print(f"brdfz view: no sphere: {e}", file=sys.stderr)
    step("sphere shader (WGSL)")
    materials: List[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        shown = [(pathlib.Path(f).name, b, os.fspath(f), os.path.getsize(f)) for f, b in zip(files, loaded)]
        shown += [(spec.split(":")[0] + f" ({b.nbytes:,} B)", b, spec, b.nbytes) for spec, b in zip(compare, built)]
        for k, (label, brdf, source, nbytes) in enumerate(shown):
            rt = sphere_layout(brdf, pathlib.Path(tmp) / f"{k}.brdfzrt")
            materials.append(_material(label, brdf, rt, source, nbytes))
            step(label)
    lobe_dirs = lobe_directions()
    wi, _ = slice_directions()
    return {
        "materials": materials, "b": len(files) if compare else min(1, len(files) - 1),
        "theta_i": list(THETA_I), "polar_angles": _f32(POLAR_ANGLES),
        "lobe_res": list(LOBE_RES), "lobe_dirs": _f32(lobe_dirs),
        "slice_res": SLICE_RES, "slice_phi_d": SLICE_PHI_D, "slice_wi_elevation": _f32(plot._elevation(wi)),
        "albedo_theta": _f32(ALBEDO_THETA),
        "sphere": {"wgsl": code, "missing": missing, "size": size, "env_samples": env_samples, "seed": 1, "passes": passes,
                   "irradiance": report.LIGHT_IRRADIANCE, "light": [float(v) for v in report.LIGHT]},
    }


def page(data: dict) -> str:
    """One self-contained HTML page: the template with the style, the script and the data inline."""
    text = (HERE / "page.html").read_text(encoding="utf-8")
    # "</" would end the script element early inside JSON strings.
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return (text.replace("/*BRDFZ_STYLE*/", (HERE / "view.css").read_text(encoding="utf-8"))
                .replace("/*BRDFZ_SCRIPT*/", (HERE / "view.js").read_text(encoding="utf-8"))
                .replace("/*BRDFZ_DATA*/", payload))


def write_html(path, html: str) -> None:
    """Atomically: a failure leaves no partial page."""
    report.atomic_write(pathlib.Path(path), lambda f: f.write(html))


def serve(html: str, port: int = 0, ready=None) -> None:
    """Serves the page at http://127.0.0.1:port/ (0: a free port) until interrupted; `ready(url)` is
    called once it listens (default: prints the URL)."""
    body = html.encode("utf-8")

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            if self.path.split("?")[0] not in ("/", "/index.html"):
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):  # requests are not news
            pass

    with http.server.ThreadingHTTPServer(("127.0.0.1", port), Handler) as server:
        url = f"http://127.0.0.1:{server.server_address[1]}/"
        if ready is None:
            print(f"serving {url} (Ctrl-C stops)", flush=True)
        else:
            ready(url)
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            pass


def main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="brdfz view", description="A local web page of materials and their representations.")
    parser.add_argument("files", nargs="+", metavar="FILE", help="materials brdfz.load reads")
    parser.add_argument("--compare", nargs="+", default=[], metavar="SPEC",
                        help="representations of the first FILE to show (brdfz compress's specs)")
    parser.add_argument("--port", type=int, default=0, help="port on 127.0.0.1 (default: a free one)")
    parser.add_argument("--html", metavar="OUT", help="write a self-contained page and exit")
    parser.add_argument("--size", type=int, default=256, help="the sphere's side in pixels (default 256)")
    parser.add_argument("--env-samples", type=int, default=64, help="sky draws per pixel of the sphere and pass (default 64)")
    parser.add_argument("--passes", type=int, default=16,
                        help="passes of sky draws the spheres and their error average, shown as they come (default 16)")
    args = parser.parse_args(argv)
    if not 0 <= args.port < 65536:
        parser.error(f"--port must be in [0, 65535], not {args.port}")
    if not 1 <= args.size <= 2048:
        parser.error(f"--size must be in [1, 2048], not {args.size}")
    if not 0 <= args.env_samples <= 4096:
        parser.error(f"--env-samples must be in [0, 4096], not {args.env_samples}")
    if not 1 <= args.passes <= 1024:
        parser.error(f"--passes must be in [1, 1024], not {args.passes}")
    try:
        html = page(build(args.files, args.compare, size=args.size, env_samples=args.env_samples,
                           passes=args.passes))
        if args.html:
            write_html(args.html, html)
            print(f"wrote {args.html} ({len(html.encode()):,} bytes)")
            return 0
        serve(html, args.port)
    except KeyboardInterrupt:
        return 130
    except (OSError, ValueError, RuntimeError) as e:
        message = f"{e.filename}: {e.strerror}" if isinstance(e, OSError) and e.filename and e.strerror else e
        print(f"brdfz view: {message}", file=sys.stderr)
        return 1
    return 0
