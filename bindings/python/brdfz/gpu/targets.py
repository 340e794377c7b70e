"""The shaders in every shading language brdfz emits: Slang's own targets (slang.TARGETS), and GLSL ES
3.10 (OpenGL ES 3.1 compute), which Slang does not write: its Vulkan GLSL compiled to SPIR-V by
glslang, then translated by SPIRV-Cross (Debian's glslang-tools and spirv-cross)."""

import shutil
import subprocess
import tempfile
from pathlib import Path

from . import slang

TARGETS = (*slang.TARGETS, "essl")


def emit(entry: str, target: str, source=None) -> bytes:
    """Entry point `entry` of the shaders (check.slang unless `source`) in `target` (TARGETS)."""
    source = source or slang.SHADERS / "check.slang"
    if target != "essl":
        return slang.compile_entry(source, entry, target)
    tools = {name: shutil.which(name) for name in ("glslangValidator", "spirv-cross")}
    missing = [name for name, path in tools.items() if not path]
    if missing:
        raise slang.SlangError(f"GLSL ES needs {' and '.join(missing)} (Debian: glslang-tools, spirv-cross)")
    with tempfile.TemporaryDirectory() as tmp:
        glsl, spv = Path(tmp) / f"{entry}.comp", Path(tmp) / f"{entry}.spv"
        glsl.write_bytes(slang.compile_entry(source, entry, "glsl"))
        for args in ([tools["glslangValidator"], "-V", str(glsl), "-o", str(spv)],
                     [tools["spirv-cross"], "--es", "--version", "310", str(spv), "--output", str(glsl)]):
            r = subprocess.run(args, capture_output=True, text=True)
            if r.returncode != 0:
                raise slang.SlangError(f"{Path(args[0]).name}: {entry} for essl: {(r.stdout + r.stderr).strip()}")
        return glsl.read_bytes()
