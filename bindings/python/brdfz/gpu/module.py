"""The per-shading-point module for renderers whose shaders are not Slang: brdfz_eval(wi, wo),
brdfz_pdf(wo, wi) and brdfz_sample(wo, u) -> BrdfzSample {wi, pdf, weight}, with the material's two
bindings, in GLSL, GLSL ES 3.10, HLSL, WGSL, CUDA or Metal, for the renderer to include in (or paste into) its own
shader and call (Metal's functions take a last argument, a BrdfzContext* holding the two buffers). Slang translates shaders/module.slang, whose entry point only keeps the three
functions in its output; that entry point and its buffer are cut out here, and the public names lose
Slang's numeric suffixes. Each step checks that it found what it cuts, so that a Slang whose output
differs fails here rather than writing a broken module."""

import re

from . import slang
from .targets import emit

MODULE_TARGETS = ("glsl", "essl", "hlsl", "wgsl", "cuda", "metal")
EXTENSIONS = {"glsl": "glsl", "essl": "essl", "hlsl": "hlsl", "wgsl": "wgsl", "cuda": "cuh", "metal": "metal"}
PUBLIC = ("brdfz_eval", "brdfz_pdf", "brdfz_sample", "BrdfzSample")
ENTRY = "brdfz_module"
# The entry point's first line per target, and the attribute lines Slang writes above it.
_ENTRY_LINE = {"glsl": r"void main\(\)", "essl": r"void main\(\)", "hlsl": rf"void {ENTRY}\(", "wgsl": rf"fn {ENTRY}\(",
               "cuda": rf'extern "C" __global__ void {ENTRY}\(', "metal": rf"\[\[kernel\]\] void {ENTRY}\("}
_ATTRIBUTES = r"(layout\(local_size_x|\[numthreads\(|@compute|@workgroup_size\()"


class ModuleError(RuntimeError):
    pass


def _cut_entry(lines: list, target: str) -> list:
    at = [i for i, line in enumerate(lines) if re.match(_ENTRY_LINE[target], line)]
    if len(at) != 1:
        raise ModuleError(f"the {target} translation has {len(at)} definitions of its entry point, not 1")
    start = end = at[0]
    while start > 0 and re.match(_ATTRIBUTES, lines[start - 1]):
        start -= 1
    depth, opened = 0, False
    while end < len(lines):
        depth += lines[end].count("{") - lines[end].count("}")
        opened |= "{" in lines[end]
        if opened and depth == 0:
            break
        end += 1
    if not opened or depth != 0:
        raise ModuleError(f"the {target} translation's entry point has no closed body")
    return lines[:start] + lines[end + 1:]


def _cut_anchor(code: str, target: str) -> str:
    if target in ("glsl", "essl"):  # a buffer block over several lines
        code, n = re.subn(rf"layout\([^)]*\) buffer \w+\s*\{{[^}}]*\}}\s*{ENTRY}_out_\d+;\n", "", code)
    else:  # a declaration, or a field of CUDA's GlobalParams or Metal's KernelContext
        code, n = re.subn(rf"[^\n]*\b{ENTRY}_out_\d+\b[^\n]*\n", "", code)
    if n != 1:
        raise ModuleError(f"the {target} translation declares the entry point's buffer {n} times, not once")
    return code


def _rename(code: str, target: str) -> str:
    for name in PUBLIC:
        code, n = re.subn(rf"\b{name}_\d+\b", name, code)
        if n == 0:
            raise ModuleError(f"the {target} translation has no {name}")
    body = re.search(r"struct BrdfzSample\s*\{(.*?)\}", code, re.S)
    fields = re.findall(r"\b(wi|pdf|weight)_\d+\b", body.group(1)) if body else []
    if sorted(fields) != ["pdf", "weight", "wi"]:
        raise ModuleError(f"the {target} translation's BrdfzSample has fields {fields}")
    for suffixed in re.findall(r"\b(?:wi|pdf|weight)_\d+\b", body.group(1)):
        code = re.sub(rf"\b{suffixed}\b", suffixed.rsplit("_", 1)[0], code)
    return code


def module(target: str) -> bytes:
    """The module in `target` (MODULE_TARGETS) as UTF-8 source. GLSL's and GLSL ES's have no #version line
    or workgroup size: a renderer's shader gives its own (450 or later; 310 es) and includes the module
    before its other declarations."""
    if target not in MODULE_TARGETS:
        raise ValueError(f"no per-shading-point module for '{target}' (one of {', '.join(MODULE_TARGETS)})")
    if target == "essl":  # Slang's GLSL through SPIR-V to SPIRV-Cross, which keeps the functions' names
        code = emit(ENTRY, "essl", slang.SHADERS / "module.slang").decode()
    else:
        code = slang.compile_entry(slang.SHADERS / "module.slang", ENTRY, target,
                                   options=("-line-directive-mode", "none")).decode()
    if target in ("glsl", "essl"):
        code = re.sub(r"\A#version \d+( es)?\n", "", code)
        code, n = re.subn(r"^layout\(local_size_x[^\n]*\) in;\n", "", code, flags=re.M)
        if n != 1:
            raise ModuleError(f"the {target} translation declares {n} workgroup sizes, not 1")
    code = "\n".join(_cut_entry(code.split("\n"), target))
    code = _rename(_cut_anchor(code, target), target)
    if target == "metal":  # the struct of bindings every function takes last, by a name a renderer can write
        code, n = re.subn(r"\bKernelContext_\d+\b", "BrdfzContext", code)
        if not re.search(r"struct BrdfzContext\b", code):
            raise ModuleError("the metal translation has no KernelContext struct")
    if ENTRY in code:
        raise ModuleError(f"the {target} translation still names {ENTRY}")
    return code.encode()
