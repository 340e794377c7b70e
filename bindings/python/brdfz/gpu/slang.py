"""The Slang compiler, as the ``slangpy`` wheel ships it: a shared library without a ``slangc``
executable, reached here through its C API (``spCompile`` with slangc's command-line arguments). It
translates the one shader source (bindings/gpu/shaders) to each shading language."""

import ctypes
import functools
import glob
import importlib.util
import os
from pathlib import Path

SHADERS = Path(__file__).parent / "shaders"

# brdfz's target names -> slangc's. Text targets give source code, spirv a binary module.
TARGETS = {"wgsl": "wgsl", "glsl": "glsl", "hlsl": "hlsl", "cuda": "cuda", "metal": "metal", "spirv": "spirv"}


class SlangError(RuntimeError):
    pass


@functools.lru_cache(maxsize=None)
def _api():
    # The wheel's folder, without importing slangpy (which starts its own GPU runtime).
    spec = importlib.util.find_spec("slangpy")
    if spec is None or not spec.submodule_search_locations:
        raise SlangError("the Slang compiler needs the slangpy wheel (pip install slangpy)")
    folder = spec.submodule_search_locations[0]
    found = sorted(glob.glob(os.path.join(folder, "libslang-compiler.so*")) + glob.glob(os.path.join(folder, "slang-compiler.dll")) +
                   glob.glob(os.path.join(folder, "libslang-compiler*.dylib")))
    if not found:
        raise SlangError(f"the slangpy wheel ({folder}) holds no Slang compiler library")
    lib = ctypes.CDLL(found[0])
    lib.spCreateSession.restype = ctypes.c_void_p
    lib.spCreateSession.argtypes = [ctypes.c_char_p]
    lib.spCreateCompileRequest.restype = ctypes.c_void_p
    lib.spCreateCompileRequest.argtypes = [ctypes.c_void_p]
    lib.spDestroyCompileRequest.argtypes = [ctypes.c_void_p]
    lib.spProcessCommandLineArguments.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_char_p), ctypes.c_int]
    lib.spCompile.argtypes = [ctypes.c_void_p]
    lib.spGetDiagnosticOutput.argtypes = [ctypes.c_void_p]
    lib.spGetDiagnosticOutput.restype = ctypes.c_char_p
    lib.spGetCompileRequestCode.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)]
    lib.spGetCompileRequestCode.restype = ctypes.c_void_p
    return lib, lib.spCreateSession(None)


@functools.lru_cache(maxsize=None)
def compile_entry(source: str, entry: str, target: str, stage: str = "compute", include: tuple = (), options: tuple = ()) -> bytes:
    """The entry point `entry` of the Slang file `source` (a path; its folder, then the folders of
    `include`, are searched for includes) in `target` (TARGETS), with slangc's `options` besides:
    source code as UTF-8, or SPIR-V words. Warnings are errors, so that a translation that Slang doubts
    fails here rather than on a user's GPU."""
    lib, session = _api()
    if target not in TARGETS:
        raise ValueError(f"unknown target '{target}' (one of {', '.join(TARGETS)})")
    request = lib.spCreateCompileRequest(session)
    try:
        folders = [os.fspath(Path(source).parent), *map(os.fspath, include)]
        args = [os.fspath(source), *[a for f in folders for a in ("-I", f)], "-target", TARGETS[target],
                "-entry", entry, "-stage", stage, "-warnings-as-errors", "all", *options]
        argv = (ctypes.c_char_p * len(args))(*[a.encode() for a in args])
        failed = lib.spProcessCommandLineArguments(request, argv, len(args)) != 0 or lib.spCompile(request) != 0
        diagnostics = (lib.spGetDiagnosticOutput(request) or b"").decode(errors="replace").strip()
        if failed:
            raise SlangError(f"slang: {entry} for {target}: {diagnostics}")
        size = ctypes.c_size_t(0)
        # The request's whole output (one entry point): spGetEntryPointCode has none for SPIR-V, Metal or CUDA.
        code = lib.spGetCompileRequestCode(request, ctypes.byref(size))
        if not code or size.value == 0:
            raise SlangError(f"slang: {entry} for {target}: no code")
        return ctypes.string_at(code, size.value)
    finally:
        lib.spDestroyCompileRequest(request)
