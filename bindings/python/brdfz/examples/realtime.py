"""A lit sphere rendered on the GPU through the exported shaders, against the CPU reference.

    python -m brdfz.examples.realtime FILE [--repr SPEC] [--size 256] [--env-samples 64] [--seed 1]
        [--png OUT.png] [--backend wgpu]

FILE is any material brdfz.load reads, exported to the runtime layout as its --repr representation
(by default DEFAULT_REPR), or a runtime layout (.brdfzrt) used as it is. An application shader
(bindings/gpu/shaders/examples/sphere.slang, which includes brdfz.slang) renders
brdfz.report.render_sphere's scene offscreen with wgpu, entirely on the GPU: an orthographic unit
sphere lit by a sun (brdfz_eval·cosθi·E) and by report.py's sky, integrated with brdfz_sample's
draws. The CPU reference is render_sphere on the same layout read by the C++ library, with the same
draws' u (`draws`, which the shader computes bit for bit), so the two differ only by the shaders'
float arithmetic against the library's double: not by Monte Carlo noise.

PSNR is taken on linear radiance over the sphere's pixels (all three channels), with the peak the
reference's 99th-percentile luminance: the "bright pixel" that report.py's exposure maps to 0.8, not
the maximum, which a sun's highlight on a glossy material would set far above the rest of the image.
Exit status 1 below MIN_PSNR, 2 when the material, the backend or the shaders fail.
"""
from __future__ import annotations

import argparse
import math
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

import brdfz
from brdfz import report
from brdfz.gpu import BackendUnavailable, Layout, SlangError, export, slang, wgpu_backend

DEFAULT_REPR = "svd:rank=10,space=cos,colour=shared,res=25x20x14,dwarp=0.9,fit=lsq,symmetry=bilateral,dtype=f16"
MIN_PSNR = 40.0
SPHERE = slang.SHADERS / "examples" / "sphere.slang"
WORKGROUP = 8  # sphere.slang's numthreads, in x and y
# At most this many draws (pixels × draws per pixel) per dispatch, so that none runs long enough for a
# driver's watchdog, and the progress line moves.
EVALS_PER_DISPATCH = 1 << 20


def _material(path, repr, workdir):
    """What a renderer ships, as `brdfz export --target slang` writes it into `workdir`/gpu (the buffers
    and the shaders), and the runtime layout the library reads for the reference: a .brdfzrt as it is
    (without `repr`), or the file's `repr` representation. Returns (layout path, export folder)."""
    rt = pathlib.Path(path)
    if repr is not None or brdfz.format_of(os.fspath(path)) != "brdfzrt":
        rt = pathlib.Path(workdir) / "material.brdfzrt"
        brdfz.export(path, rt, repr=repr or DEFAULT_REPR)
    folder = pathlib.Path(workdir) / "gpu"
    export(rt, folder, "slang")
    return rt, folder


def _pcg_hash(v: np.ndarray) -> np.ndarray:
    """sphere.slang's pcg_hash on uint32 arrays (wrapping arithmetic)."""
    v = np.asarray(v, np.uint32)
    state = v * np.uint32(747796405) + np.uint32(2891336453)
    word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
    return (word >> np.uint32(22)) ^ word


def _stratification(env_samples: int):
    """(side, float32(1 / side)): the first side² draws are jittered strata, as render_sphere's."""
    side = max(math.isqrt(env_samples), 1)
    return side, np.float32(1.0 / side)


def draws(env_samples: int, seed: int = 1):
    """The u of sphere.slang's sphere_u as render_sphere's `draws`: (k, pixels) -> (len(pixels), 2),
    in float32 steps that are exact or correctly rounded, so the bits are the shader's."""
    side, inv_side = _stratification(env_samples)
    scale = np.float32(2.0 ** -24)
    below_one = np.nextafter(np.float32(1), np.float32(0))

    def u(k: int, pixels: np.ndarray) -> np.ndarray:
        key = _pcg_hash(_pcg_hash(np.array([seed], np.uint32)) ^ np.asarray(pixels, np.uint32))
        bits = np.stack([_pcg_hash(key + np.uint32(2 * k)), _pcg_hash(key + np.uint32(2 * k + 1))], axis=1)
        r = (bits >> np.uint32(8)).astype(np.float32) * scale
        if k < side * side:
            cell = np.array([k % side, k // side], np.float32)
            r = np.minimum((cell + r) * inv_side, below_one)
        return r.astype(np.float64)

    return u


def reference(brdf: brdfz.Brdf, size: int, env_samples: int, seed: int = 1, progress=None) -> np.ndarray:
    """The CPU render (the C++ library through render_sphere) with the shader's u; `progress` (a
    report.Bar or None) steps progress.total times over the draws."""
    u = draws(env_samples, seed)

    def stepped(k, pixels):
        if progress is not None and (k + 1) * progress.total // env_samples > k * progress.total // env_samples:
            progress.step(f"draw {k + 1}")
        return u(k, pixels)

    return report.render_sphere(brdf, size, env_samples, draws=stepped)


class SphereRenderer:
    """sphere.slang's sphere_render on wgpu (a GPU, or Mesa's lavapipe where there is none), its
    includes from `shaders` (the folder holding brdfz.slang)."""

    def __init__(self, shaders=slang.SHADERS):
        wgpu, adapter = wgpu_backend.start()
        self.wgpu = wgpu
        self.adapter = adapter.info.get("device", "?")
        self.software = adapter.info.get("adapter_type", "") == "CPU"
        self.limit = adapter.limits["max-storage-buffer-binding-size"]
        self.device = adapter.request_device_sync(required_limits={"max-storage-buffer-binding-size": self.limit})
        t = time.perf_counter()
        code = slang.compile_entry(os.fspath(SPHERE), "sphere_render", "wgsl", include=(os.fspath(shaders),))
        storage = {"type": wgpu.BufferBindingType.read_only_storage}
        stage = wgpu.ShaderStage.COMPUTE
        self.group_layout = self.device.create_bind_group_layout(entries=[
            {"binding": 0, "visibility": stage, "buffer": storage},
            {"binding": 1, "visibility": stage, "buffer": storage},
            {"binding": 2, "visibility": stage, "buffer": {"type": wgpu.BufferBindingType.uniform}},
            {"binding": 3, "visibility": stage, "buffer": {"type": wgpu.BufferBindingType.storage}}])
        self.pipeline = self.device.create_compute_pipeline(
            layout=self.device.create_pipeline_layout(bind_group_layouts=[self.group_layout]),
            compute={"module": self.device.create_shader_module(code=code.decode()), "entry_point": "sphere_render"})
        self.compile_seconds = time.perf_counter() - t

    def render(self, layout: Layout, size: int, env_samples: int, seed: int = 1, progress=None) -> np.ndarray:
        """Linear RGB (size, size, 3) of render_sphere's scene (its default light) for `layout`;
        `progress` (a report.Bar or None) steps once per dispatch. Sets self.render_seconds: submit to
        read-back."""
        wgpu = self.wgpu
        if not (isinstance(size, int) and 1 <= size and 12 * size * size <= self.limit):
            raise ValueError(f"size must be an integer in [1, {math.isqrt(self.limit // 12)}] here, not {size!r}")
        if len(layout.data) > self.limit:
            raise BackendUnavailable(f"the layout's {len(layout.data)} bytes exceed the adapter's storage buffer limit ({self.limit})")
        storage = wgpu.BufferUsage.STORAGE
        material = self.device.create_buffer_with_data(data=layout.data, usage=storage)
        desc = self.device.create_buffer_with_data(data=layout.desc.tobytes(), usage=storage)
        out = self.device.create_buffer(size=12 * size * size, usage=storage | wgpu.BufferUsage.COPY_SRC)
        side, inv_side = _stratification(env_samples)
        groups = (size + WORKGROUP - 1) // WORKGROUP
        t = time.perf_counter()
        # The first dispatch writes the sun's term over whatever the buffer held; the others add.
        for first, count in dispatches(size, env_samples):
            params = np.zeros(1, [("size", "<u4"), ("env_samples", "<u4"), ("first", "<u4"), ("count", "<u4"),
                                  ("seed", "<u4"), ("side", "<u4"), ("inv_side", "<f4"), ("irradiance", "<f4"),
                                  ("light", "<f4", 3)])
            params[0] = (size, env_samples, first, count, seed, side, inv_side, report.LIGHT_IRRADIANCE, report.LIGHT)
            uniform = params.tobytes() + b"\0" * (-params.nbytes % 16)
            group = self.device.create_bind_group(layout=self.group_layout, entries=[
                {"binding": 0, "resource": {"buffer": material}},
                {"binding": 1, "resource": {"buffer": desc}},
                {"binding": 2, "resource": {"buffer": self.device.create_buffer_with_data(
                    data=uniform, usage=wgpu.BufferUsage.UNIFORM)}},
                {"binding": 3, "resource": {"buffer": out}}])
            encoder = self.device.create_command_encoder()
            compute = encoder.begin_compute_pass()
            compute.set_pipeline(self.pipeline)
            compute.set_bind_group(0, group)
            compute.dispatch_workgroups(groups, groups)
            compute.end()
            self.device.queue.submit([encoder.finish()])
            if progress is not None:
                # Waits for the dispatch (wgpu-py's on_submitted_work_done_sync fails in some versions).
                self.device.queue.read_buffer(out, 0, 4)
                progress.step(f"draws {first + 1}-{first + count}" if count else "sun")
        image = np.frombuffer(self.device.queue.read_buffer(out), np.float32).reshape(size, size, 3)
        self.render_seconds = time.perf_counter() - t
        return image


def dispatches(size: int, env_samples: int):
    """(first, count) of the draws of each dispatch; one without draws writes the sun's term alone."""
    per = max(1, min(env_samples, EVALS_PER_DISPATCH // (size * size)))
    return [(first, min(per, env_samples - first)) for first in range(0, max(env_samples, 1), per)]


def sphere_mask(size: int) -> np.ndarray:
    """The pixels whose centres lie inside the unit disc, as render_sphere and sphere.slang draw them."""
    c = 2 * np.arange(size) + 1 - size
    return c[None, :] ** 2 + c[:, None] ** 2 < size * size


def psnr(image: np.ndarray, ref: np.ndarray) -> float:
    """PSNR in dB of `image` against `ref` (linear RGB, (size, size, 3)) over the sphere's pixels and
    channels, the peak the reference's 99th-percentile luminance there (mean of the channels); inf
    where they are equal."""
    inside = sphere_mask(ref.shape[0])
    a, b = np.asarray(image, np.float64)[inside], np.asarray(ref, np.float64)[inside]
    peak = float(np.percentile(b.mean(axis=1), 99))
    mse = float(np.mean((a - b) ** 2))
    if not (peak > 0):
        raise ValueError("the reference is black: no peak to measure against")
    return math.inf if mse == 0 else 10 * math.log10(peak * peak / mse)


def write_png(path, image: np.ndarray, ref: np.ndarray, title: str) -> None:
    """GPU and CPU renders side by side, tone-mapped with the reference's exposure, and their absolute
    difference relative to the PSNR's peak."""
    plt = report._plt()
    exposure = report.exposure_of(ref)
    diff = np.abs(np.asarray(image, np.float64) - ref).mean(axis=2) * exposure / 0.8
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.6))
    axes[0].imshow(report.tone_map(image, exposure))
    axes[0].set_title("GPU (sphere.slang)", fontsize=9)
    axes[1].imshow(report.tone_map(ref, exposure))
    axes[1].set_title("CPU reference (C++ library)", fontsize=9)
    shown = axes[2].imshow(diff, cmap="magma", vmin=0)
    axes[2].set_title("|GPU − CPU| / peak", fontsize=9)
    for ax in axes:
        ax.axis("off")
    fig.colorbar(shown, ax=axes[2], shrink=0.8)
    fig.suptitle(title, fontsize=9)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m brdfz.examples.realtime",
                                     description="A lit sphere through the exported shaders (wgpu) against the CPU reference.")
    parser.add_argument("file", help="a material brdfz.load reads, or a runtime layout (.brdfzrt)")
    parser.add_argument("--repr", help=f"the representation to export (default for a file that is not a .brdfzrt: {DEFAULT_REPR})")
    parser.add_argument("--size", type=int, default=256, help="image side in pixels (default 256)")
    parser.add_argument("--env-samples", type=int, default=64, help="environment draws per pixel (default 64)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--png", help="write GPU, CPU and their difference side by side")
    parser.add_argument("--backend", default="wgpu", choices=["wgpu"])
    args = parser.parse_args(argv)
    if not 1 <= args.size <= 8192:
        parser.error(f"--size must be in [1, 8192], not {args.size}")
    if not 0 <= args.env_samples <= 1 << 16:
        parser.error(f"--env-samples must be in [0, 65536], not {args.env_samples}")
    if not 0 <= args.seed < 1 << 32:
        parser.error(f"--seed must be in [0, 2³²), not {args.seed}")
    try:
        with tempfile.TemporaryDirectory() as tmp:
            print(f"loading {args.file} ...", file=sys.stderr, flush=True)
            rt, folder = _material(args.file, args.repr, tmp)
            layout = Layout.from_export(folder)
            ref_brdf = brdfz.load(rt)
            nbytes = os.path.getsize(rt)
            gpu = SphereRenderer(shaders=folder / "shaders")
        image = gpu.render(layout, args.size, args.env_samples, args.seed,
                           progress=report.Bar("GPU render", len(dispatches(args.size, args.env_samples))))
        t = time.perf_counter()
        ref = reference(ref_brdf, args.size, args.env_samples, args.seed,
                        progress=report.Bar("CPU reference", min(args.env_samples, 8)) if args.env_samples else None)
        cpu_seconds = time.perf_counter() - t
        value = psnr(image, ref)
        speed = "software rendering on the CPU: the speed means nothing here" if gpu.software else "a GPU"
        print(f"{args.file}: {ref_brdf.describe()} ({nbytes:,} bytes)")
        print(f"  {args.size}x{args.size}, sun and sky, {args.env_samples} environment draws per pixel, seed {args.seed}")
        print(f"  GPU  wgpu on {gpu.adapter} ({speed}): render {gpu.render_seconds:.2f} s, "
              f"shader compile {gpu.compile_seconds:.2f} s")
        print(f"  CPU  reference through the C++ library: {cpu_seconds:.2f} s")
        print(f"  PSNR {value:.2f} dB (linear radiance over the sphere, peak the reference's 99th-percentile "
              f"luminance): {'ok' if value >= MIN_PSNR else 'FAILED'}, at least {MIN_PSNR:g} dB")
        if args.png:
            write_png(args.png, image, ref, f"{pathlib.Path(args.file).name}: PSNR {value:.1f} dB")
            print(f"  wrote {args.png}")
    except (OSError, ValueError, BackendUnavailable, SlangError) as e:
        message = f"{e.filename}: {e.strerror}" if isinstance(e, OSError) and e.filename and e.strerror else e
        print(f"brdfz.examples.realtime: {message}", file=sys.stderr)
        return 2
    return 0 if value >= MIN_PSNR else 1


if __name__ == "__main__":
    sys.exit(main())
