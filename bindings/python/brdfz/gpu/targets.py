"""The shaders in every shading language brdfz emits: Slang's own targets (slang.TARGETS), and GLSL ES,
which Slang does not write: its Vulkan GLSL compiled to SPIR-V by glslang, then translated by
SPIRV-Cross (Debian's glslang-tools and spirv-cross). GLSL ES 3.10 for compute entry points (OpenGL ES
3.1, the kernels `brdfz export --target essl` writes); 3.00 for webgl.slang's vertex and fragment entry
points (WebGL2, which has no compute shaders)."""

import functools
import shutil
import subprocess
import tempfile
from pathlib import Path

from . import slang

TARGETS = (*slang.TARGETS, "essl")

# webgl.slang's entry points and their stages.
WEBGL_ENTRIES = {"webgl_vertex": "vertex", "webgl_eval": "fragment", "webgl_rounding": "fragment",
                 "webgl_pdf": "fragment", "webgl_sample": "fragment"}


@functools.lru_cache(maxsize=None)
def emit(entry: str, target: str, source=None) -> bytes:
    """Entry point `entry` of the shaders in `target` (TARGETS): of check.slang's compute entry points,
    or webgl.slang's (WEBGL_ENTRIES, essl only), unless `source`."""
    if entry in WEBGL_ENTRIES:
        if target != "essl":
            raise ValueError(f"{entry} is WebGL2's, emitted as essl only")
        return _essl(source or slang.SHADERS / "webgl.slang", entry, WEBGL_ENTRIES[entry], "300")
    source = source or slang.SHADERS / "check.slang"
    if target != "essl":
        return slang.compile_entry(source, entry, target)
    return _essl(source, entry, "compute", "310")


def _essl(source, entry, stage, version):
    tools = {name: shutil.which(name) for name in ("glslangValidator", "spirv-cross")}
    missing = [name for name, path in tools.items() if not path]
    if missing:
        raise slang.SlangError(f"GLSL ES needs {' and '.join(missing)} (Debian: glslang-tools, spirv-cross)")
    with tempfile.TemporaryDirectory() as tmp:
        glsl = Path(tmp) / f"{entry}.{ {'compute': 'comp', 'vertex': 'vert', 'fragment': 'frag'}[stage] }"
        spv = Path(tmp) / f"{entry}.spv"
        glsl.write_bytes(slang.compile_entry(source, entry, "glsl", stage))
        # GLSL ES 3.00 has no arrays of arrays (Slang's struct packing writes some). Precision needs no
        # option: Slang's SPIR-V has no relaxed precision, so SPIRV-Cross declares every variable highp.
        flatten = ["--flatten-multidimensional-arrays"] if version == "300" else []
        for args in ([tools["glslangValidator"], "-V", str(glsl), "-o", str(spv)],
                     [tools["spirv-cross"], "--es", "--version", version, *flatten, str(spv), "--output", str(glsl)]):
            r = subprocess.run(args, capture_output=True, text=True)
            if r.returncode != 0:
                raise slang.SlangError(f"{Path(args[0]).name}: {entry} for essl: {(r.stdout + r.stderr).strip()}")
        return glsl.read_bytes()
