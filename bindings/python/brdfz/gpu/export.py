"""brdfz export IN -o DIR --target T (python -m brdfz.gpu export): a material for a GPU renderer. DIR gets

  material.bin      binding 0: the runtime layout (.brdfzrt, formats/SPEC.md §6) as it is, then float
                    copies of its float64 arrays (brdfz.gpu.Layout's data), read as 32-bit words
  descriptors.bin   binding 1: BrdfzDesc records (bindings/gpu/shaders/desc.slang), the root's first
  the shader module the target names: the kernels brdfz_eval_kernel, brdfz_pdf_kernel and
                    brdfz_sample_kernel (kernels.slang), one file each; brdfz_module.* (glsl, essl,
                    hlsl, wgsl, cuda, metal: brdfz.gpu.module) with the functions brdfz_eval, brdfz_pdf and
                    brdfz_sample a renderer's own shaders call per shading point; for `slang` the source
                    itself, whose functions those are;
                    for `essl` also WebGL2's render passes (webgl.slang: GLSL ES 3.00, which has no
                    compute shaders), which read the same two files as R32UI textures
  brdfz.json        the descriptor: bindings per target, formats, sizes, the spec and its measured error
  INTEGRATION.md    how a renderer in the target's API binds the buffers and calls the kernels

Every file is written to a temporary folder beside DIR's files and moved into place only when all are
written, so a failure leaves no partial export."""

import json
import math
import os
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np

from . import slang
from .layout import Layout, desc_dtype
from .module import EXTENSIONS as MODULE_EXTENSIONS
from .module import MODULE_TARGETS, module
from .targets import WEBGL_ENTRIES, emit

KERNELS = ("brdfz_eval_kernel", "brdfz_pdf_kernel", "brdfz_sample_kernel")
WORKGROUP = (64, 1, 1)
# Each target's file extension for the kernels (GLSL's and GLSL ES's the compute-stage one glslang reads).
EXTENSIONS = {"glsl": "comp", "essl": "comp", "hlsl": "hlsl", "wgsl": "wgsl", "cuda": "cu", "metal": "metal", "slang": "slang"}
EXPORT_TARGETS = tuple(EXTENSIONS)
# What each kernel reads and writes at bindings 2-5 (0 and 1 are the material's).
IO = {
    "brdfz_eval_kernel": ("wi: float[3n]", "wo: float[3n]", "f: float[3n], RGB, without the cosine"),
    "brdfz_pdf_kernel": ("wo: float[3n]", "wi: float[3n]", "pdf: float[n], per unit solid angle of wi"),
    "brdfz_sample_kernel": ("wo: float[3n]", "u: float[2n] in [0, 1)", "float[7n]: wi (3), pdf, weight = f·cosθi/pdf (3)"),
}
# WebGL2's passes (webgl.slang) a renderer runs: one pair or draw per pixel; webgl_rounding is the checks'.
WEBGL_PASSES = {
    "webgl_eval": ("wi", "wo", "RGBA32F: f (rgb)"),
    "webgl_pdf": ("wo", "wi", "RGBA32F: pdf (r)"),
    "webgl_sample": ("wo", "u (xy)", "two RGBA32F targets: wi and pdf (rgba), weight (rgb)"),
}
NAMES = {"brdfz_data": "material", "brdfz_desc": "descriptors", "brdfz_in_a": "a", "brdfz_in_b": "b",
         "brdfz_out": "out", "brdfz_count": "count"}
FUNCTIONS = ["float3 brdfz_eval(float3 wi, float3 wo)", "float brdfz_pdf(float3 wo, float3 wi)",
             "BrdfzSample brdfz_sample(float3 wo, float2 u)"]
CONVENTIONS = ("local frame with the normal +z; wi and wo unit vectors pointing away from the surface (non-unit "
               "ones are normalised); eval is f_r without the cosine, in linear RGB, 1/sr; pdf per unit solid angle "
               "of wi; below the horizon eval and pdf are 0 and a draw fails with pdf 0")


class ExportError(ValueError):
    pass


def _slots(target: str, code: str) -> dict:
    """Where each buffer sits in the emitted code, read from the code itself: {buffer: slot}."""
    patterns = {
        "wgsl": r"@binding\((\d+)\) @group\(\d+\) var<[^>]*> (brdfz_\w+?)_\d+ :",
        "hlsl": r"(brdfz_\w+?)_\d+ : register\((\w\d+)\)",
        "metal": r"(brdfz_\w+?)_\d+ \[\[buffer\((\d+)\)\]\]",
        "glsl": r"binding = (\d+)\) (?:readonly )?buffer \w+\s*\{[^}]*\}\s*(brdfz_\w+?)_\d+;",
        "essl": r"binding = (\d+)\) (?:readonly )?buffer \w+\s*\{[^}]*\}\s*(brdfz_\w+?)_\d+;",
    }
    found = {}
    if target == "cuda":
        body = re.search(r"struct GlobalParams_0\s*\{(.*?)\};", code, re.S)
        fields = re.findall(r"(brdfz_\w+?)_\d+;", body.group(1)) if body else []
        # Each field is a {pointer, 64-bit count} pair (the prelude's StructuredBuffer / ByteAddressBuffer).
        return {name: f"SLANG_globalParams + {16 * i} bytes" for i, name in enumerate(fields)}
    for m in re.finditer(patterns[target], code):
        name, slot = (m.group(2), m.group(1)) if m.group(1)[0].isdigit() else (m.group(1), m.group(2))
        found[name] = slot if not slot.isdigit() else int(slot)
    return found


def _webgl(folder: Path, layout, dtype) -> dict:
    """WebGL2's render passes written into `folder`, and how their textures are laid out."""
    width = int(re.search(r"#define BRDFZ_TEXTURE_WIDTH (\d+)", (slang.SHADERS / "webgl.slang").read_text()).group(1))
    files = {}
    for entry in ("webgl_vertex", *WEBGL_PASSES):
        name = f"{entry}.{'vert' if WEBGL_ENTRIES[entry] == 'vertex' else 'frag'}"
        (folder / name).write_bytes(emit(entry, "essl"))
        files[entry] = name
    words = len(layout.data) // 4
    return {
        "version": "GLSL ES 3.00",
        "vertex": files["webgl_vertex"],
        "vertex_input": "attribute 0 (corner_0): vec2 corners of a triangle covering the viewport, e.g. (-1,-1), (3,-1), (-1,3)",
        "textures": {
            "material": {"uniform": "brdfz_data_0", "file": "material.bin", "format": "R32UI", "width": width,
                         "height": -(-words // width), "note": "the file's 32-bit words row by row, the last row zero-padded"},
            "descriptors": {"uniform": "brdfz_desc_words_0", "file": "descriptors.bin", "format": "R32UI",
                            "width": dtype.itemsize // 4, "height": int(len(layout.desc)), "note": "one descriptor per row"},
        },
        "inputs": {"pair_a_0": "RGBA32F texture, one direction (xyz) per texel, the same texel as the pixel drawn",
                   "pair_b_0": "RGBA32F texture, likewise"},
        "passes": [{"entry": e, "file": files[e], "pair_a": a, "pair_b": b, "out": o} for e, (a, b, o) in WEBGL_PASSES.items()],
    }


def _measured_error(path, brdf, reference, pairs: int):
    """The representation's error against its reference over `pairs` direction pairs uniform in solid
    angle (brdfz.metrics over="directions": what a renderer sees), or the figure its .brdfz recorded."""
    import brdfz

    if reference is not None:
        m = brdfz.metrics(reference, brdf, over="directions", directions=pairs)
        return {"over": "directions", "pairs": pairs, "max_theta_deg": 80.0, "cos_rmse_rel": m.cos_rmse_rel.mean,
                "log_rmse": m.log_rmse.mean, "against": "the export's source"}
    if path is not None and brdfz.format_of(os.fspath(path)) == "brdfz":
        meta = brdfz.container_metadata(path)
        metrics = meta["achieved"]["metrics"]
        if metrics is not None:
            return {"over": "grid", "cos_rmse_rel": metrics.cos_rmse_rel.mean, "log_rmse": metrics.log_rmse.mean,
                    "against": meta["source"]["file"] or "its source", "recorded_by": "brdfz compress"}
    return None


def _integration(target: str, slots: dict) -> str:
    """INTEGRATION.md: what a renderer in the target's API does with the files."""
    where = "\n".join(f"| {NAMES[name]} | `{slot}` |" for name, slot in sorted(slots.items(), key=lambda kv: str(kv[1])))
    table = f"| buffer | slot in this module |\n|---|---|\n{where}\n" if slots else ""
    common = f"""# Using this brdfz material ({target})

`brdfz.json` lists the files, their sizes and formats, the representation and its measured error.
Conventions: {CONVENTIONS}.

Upload `material.bin` and `descriptors.bin` once, as read-only storage buffers, byte for byte (both
little-endian; the material is read as 32-bit words, so its size is a multiple of 4). The kernels
`brdfz_eval_kernel`, `brdfz_pdf_kernel` and `brdfz_sample_kernel` run one thread per item, {WORKGROUP[0]}
per workgroup; dispatch ceil(n / {WORKGROUP[0]}) groups. Inputs `a` and `b` are packed floats (three per
direction, two per u), `out` receives 3, 1 or 7 floats per item, `count` holds n as one uint:

| kernel | a | b | out |
|---|---|---|---|
""" + "\n".join(f"| `{k}` | {a} | {b} | {o} |" for k, (a, b, o) in IO.items()) + "\n\n" + table
    notes = {
        "glsl": """## Vulkan or OpenGL 4.3+ (GLSL 450 compute)

Each `.comp` file is one compute shader (GLSL names its entry point `main`). Vulkan: compile with
`glslangValidator -V brdfz_eval_kernel.comp -o eval.spv`; descriptor set 0, storage buffers at the
bindings above. OpenGL: `glShaderSource` + `glCompileShader` as `GL_COMPUTE_SHADER`, then
`glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer)` for each buffer and
`glDispatchCompute(ceil(n / 64), 1, 1)`; `glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT)` before reading
`out`.
""",
        "essl": """## OpenGL ES 3.1 (GLSL ES 3.10 compute)

As OpenGL: each `.comp` file is a compute shader for `glCreateShader(GL_COMPUTE_SHADER)`; bind the
buffers with `glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer)` and call
`glDispatchCompute(ceil(n / 64), 1, 1)`.

## WebGL2 (GLSL ES 3.00 render passes)

WebGL2 has no compute shaders or storage buffers, so `webgl_eval.frag`, `webgl_pdf.frag` and
`webgl_sample.frag` compute one pair or draw per pixel, each linked with `webgl_vertex.vert`. Upload
`material.bin` and `descriptors.bin` as `R32UI` textures (`texImage2D(TEXTURE_2D, 0, R32UI, width,
height, 0, RED_INTEGER, UNSIGNED_INT, words)`) with the widths and heights `brdfz.json`'s `webgl2.textures`
gives (the material's last row zero-padded), `NEAREST` filtering, and set the samplers `brdfz_data_0`
and `brdfz_desc_words_0` to their units. The inputs are `RGBA32F` textures `pair_a_0` and `pair_b_0`
(one direction, or u in xy, per texel); render into `RGBA32F` colour attachments (the
`EXT_color_buffer_float` extension; `webgl_sample` writes two, `drawBuffers`), a triangle covering the
viewport from attribute 0, then `readPixels(..., RGBA, FLOAT, ...)`.
""",
        "hlsl": """## Direct3D 12 (HLSL, compute shader model 5.0+)

Compile each file with DXC (`dxc -T cs_6_0 -E brdfz_eval_kernel brdfz_eval_kernel.hlsl`) or FXC
(`cs_5_0`). The material, descriptors, `a`, `b` and `count` are SRVs (structured buffers: the material a
raw `ByteAddressBuffer` view, R32_TYPELESS; descriptors a structured view with the stride `brdfz.json`
gives), `out` a UAV, at the registers above; `Dispatch(ceil(n / 64), 1, 1)`.
""",
        "wgsl": """## WebGPU (WGSL)

`device.createShaderModule({code})` per file and a compute pipeline with the file's entry point; one
bind group (group 0) with storage buffers at the bindings above (`out` read-write, the rest read-only);
`dispatchWorkgroups(ceil(n / 64))`. No f16 or f64 features are needed.
""",
        "cuda": """## CUDA (NVRTC or nvcc)

Each `.cu` file holds one `extern "C" __global__` kernel and, in Slang's CUDA prelude (the kernels
include `slang-cuda-prelude.h`, shipped with Slang; NVRTC needs its folder on the include path), the
buffer types. The kernels take no arguments: they read the buffers from the `__constant__` struct
`SLANG_globalParams`, one {device pointer, 64-bit element count (bytes for the material)} pair per
buffer, at the byte offsets above. Fill it with `cuModuleGetGlobal(&ptr, &size, module,
"SLANG_globalParams")` and `cuMemcpyHtoD`, then `cuLaunchKernel(kernel, ceil(n / 64), 1, 1, 64, 1, 1, 0,
stream, NULL, NULL)`.
""",
        "metal": """## Metal (MSL)

Compile each `.metal` file (`xcrun -sdk macosx metal -c`) or `newLibraryWithSource`; the kernel takes
the buffers as `device` arguments at the `[[buffer(n)]]` indices above (`setBuffer:offset:atIndex:`);
`dispatchThreadgroups(ceil(n / 64), threadsPerThreadgroup: 64)`.
""",
        "slang": """## Slang (any API Slang targets)

`shaders/brdfz.slang` is the source the other targets are translated from. A renderer's Slang code
`#include "brdfz.slang"` (the folder on the include path) and calls, per shading point:

```
float3 brdfz_eval(float3 wi, float3 wo)          // f without the cosine
float  brdfz_pdf(float3 wo, float3 wi)           // per unit solid angle of wi
BrdfzSample brdfz_sample(float3 wo, float2 u)    // {wi, pdf == brdfz_pdf(wo, wi), weight = f·cosθi/pdf}
```

It binds `material.bin` at set 0 binding 0 (`ByteAddressBuffer brdfz_data`) and `descriptors.bin` at
binding 1 (`StructuredBuffer<BrdfzDesc> brdfz_desc`); move them with `[[vk::binding]]` edits if the
renderer's layout needs the slots. `shaders/kernels.slang` holds the three kernels the other targets
export.
""",
    }
    return common + "\n" + notes[target] + (f"\n{_per_shading_point(target)}" if target in MODULE_TARGETS else "")


def _per_shading_point(target: str) -> str:
    """INTEGRATION.md's section on the module a renderer's own shaders include."""
    name = f"brdfz_module.{MODULE_EXTENSIONS[target]}"
    how = {
        "glsl": f"""Paste or `#include` (GL_GOOGLE_include_directive) `{name}` right after the shader's own `#version 450`
(or later) line, before its other declarations: it declares the material's two storage buffers at the
bindings above and the functions.""",
        "essl": f"""Paste `{name}` right after the shader's own `#version 310 es` line (and, in a fragment shader,
`precision highp float;`), before its other declarations: it declares the material's two storage
buffers (bindings 0 and 1) and the functions. OpenGL ES 3.1 has storage buffers in compute shaders, and
in fragment shaders where `GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS` allows; WebGL2 has none (use its
passes above).""",
        "hlsl": f"""`#include "{name}"`: it declares the material's two buffers at the registers above and the
functions.""",
        "wgsl": f"""WGSL has no includes: prepend `{name}` to the shader's source. It declares the material's two
storage buffers (group 0, the bindings above) and the functions.""",
        "cuda": f"""`#include "{name}"` in one translation unit (it defines `SLANG_globalParams`, filled as for the
kernels, with the material's two buffers) and call the `__device__` functions from your kernels.""",
        "metal": f"""`#include "{name}"`. Each function takes a last argument, a `BrdfzContext thread*` whose
`brdfz_data_0` and `brdfz_desc_0` point at the material's two buffers: fill one from your kernel's
`device` arguments and pass its address.""",
    }[target]
    return f"""## Per shading point: brdfz_eval, brdfz_pdf, brdfz_sample

{how} Per shading point, in brdfz's conventions:

```
float3 brdfz_eval(float3 wi, float3 wo)          // f without the cosine
float  brdfz_pdf(float3 wo, float3 wi)           // per unit solid angle of wi
BrdfzSample brdfz_sample(float3 wo, float2 u)    // {{wi, pdf == brdfz_pdf(wo, wi), weight = f·cosθi/pdf}}
```

(in the language's own vector types). The module's other names end in `_` and a number (Slang's); keep
your own names free of that pattern.
"""


def export(source, out_dir, target: str = "slang", *, repr=None, reference=None, error_pairs: int = 1 << 16,
           threads: int = 0, progress=None) -> dict:
    """Writes `source` (a Brdf or a file), or its `repr` representation (a compress() spec), for a GPU
    renderer in `target` (EXPORT_TARGETS) into the folder `out_dir` (created; files of the same names
    replaced): see the module's docstring. The descriptor records the representation's error against
    `reference` (default: the source when `repr` builds from it) over `error_pairs` direction pairs, or
    the error a .brdfz file recorded. Returns the descriptor as a dict."""
    import brdfz

    if target not in EXPORT_TARGETS:
        raise ExportError(f"unknown target '{target}' (one of {', '.join(EXPORT_TARGETS)})")
    if not (isinstance(error_pairs, int) and 1 <= error_pairs <= 1 << 24):
        raise ExportError(f"error_pairs must be an integer in [1, 2^24], not {error_pairs!r}")
    path = None if isinstance(source, brdfz.Brdf) else Path(source)
    brdf = source if path is None else brdfz.load(path)
    spec = brdf.describe()
    build_spec = None
    if repr:
        built = brdfz.compress(brdf, repr, report=True, threads=threads, progress=progress)
        reference = brdf if reference is None else reference
        brdf, build_spec = built.brdf, built.spec
        spec = brdf.describe()
    elif reference is not None and not isinstance(reference, brdfz.Brdf):
        reference = brdfz.load(reference)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out_dir, prefix=".brdfz-export-") as tmp:
        tmp = Path(tmp)
        rt = tmp / "material.brdfzrt"
        brdfz.save(brdf, rt, format="brdfzrt")
        layout = Layout(rt)
        layout_bytes = rt.stat().st_size
        rt.unlink()
        (tmp / "material.bin").write_bytes(layout.data)
        (tmp / "descriptors.bin").write_bytes(layout.desc.tobytes())
        files, slots = [], {}
        if target == "slang":
            (tmp / "shaders").mkdir()
            for f in sorted(slang.SHADERS.glob("*.slang")):
                if f.name not in ("check.slang", "module.slang"):  # the checks' and the exporter's own
                    shutil.copyfile(f, tmp / "shaders" / f.name)
                    files.append(f"shaders/{f.name}")
        else:
            for entry in KERNELS:
                code = emit(entry, target, slang.SHADERS / "kernels.slang")
                name = f"{entry}.{EXTENSIONS[target]}"
                (tmp / name).write_bytes(code)
                files.append(name)
                slots.update(_slots(target, code.decode()))
            if target in MODULE_TARGETS:
                name = f"brdfz_module.{MODULE_EXTENSIONS[target]}"
                (tmp / name).write_bytes(module(target))
                files.append(name)
        error = _measured_error(path, brdf, reference, error_pairs)
        dtype = desc_dtype()
        descriptor = {
            "brdfz_gpu_export": 1,
            "target": target,
            "representation": spec,
            "build_spec": build_spec,
            "source": None if path is None else path.name,
            "bytes": brdf.nbytes,
            "error": error,
            "conventions": CONVENTIONS,
            "buffers": [
                {"name": "material", "file": "material.bin", "bytes": len(layout.data), "slot": slots.get("brdfz_data", 0),
                 "format": "little-endian bytes read as 32-bit words: the runtime layout (formats/SPEC.md §6) "
                           f"in its first {layout_bytes} bytes, then float32 copies of its float64 arrays"},
                {"name": "descriptors", "file": "descriptors.bin", "bytes": int(layout.desc.nbytes),
                 "slot": slots.get("brdfz_desc", 1), "format": "array of BrdfzDesc (desc.slang): the root's, then a "
                 "φh stack's slices'", "count": int(len(layout.desc)), "stride": dtype.itemsize,
                 "fields": [[name, {"<u4": "uint", "<i4": "int", "<f4": "float"}[dtype.fields[name][0].str]]
                            for name in dtype.names]},
            ],
            "kernels": [{"entry": entry, "file": f"{entry}.{EXTENSIONS[target]}", "workgroup_size": list(WORKGROUP),
                         "a": IO[entry][0], "b": IO[entry][1], "out": IO[entry][2]} for entry in KERNELS],
            "io_slots": {NAMES[k]: v for k, v in slots.items() if k not in ("brdfz_data", "brdfz_desc")} if slots else
                        {"a": 2, "b": 3, "out": 4, "count": 5},
            "module": "shaders/brdfz.slang" if target == "slang" else
                      f"brdfz_module.{MODULE_EXTENSIONS[target]}" if target in MODULE_TARGETS else None,
            "functions": FUNCTIONS if target == "slang" or target in MODULE_TARGETS else None,
            "files": ["material.bin", "descriptors.bin", *files, "brdfz.json", "INTEGRATION.md"],
            "integration": "INTEGRATION.md",
        }
        if target == "slang":
            descriptor["kernels"] = [dict(k, file="shaders/kernels.slang") for k in descriptor["kernels"]]
        if target == "essl":
            descriptor["webgl2"] = _webgl(tmp, layout, dtype)
            descriptor["files"][-2:-2] = [descriptor["webgl2"]["vertex"]] + [p["file"] for p in descriptor["webgl2"]["passes"]]
        (tmp / "INTEGRATION.md").write_text(_integration(target, slots))
        (tmp / "brdfz.json").write_text(json.dumps(descriptor, indent=2, allow_nan=False) + "\n")
        for name in descriptor["files"]:
            target_path = out_dir / name
            target_path.parent.mkdir(parents=True, exist_ok=True)
            os.replace(tmp / name, target_path)
    return descriptor
