"""brdfz on the GPU: the shaders of bindings/gpu/shaders (one Slang source, translated to each shading
language by the Slang compiler) and their check against the C++ library on software or real GPUs.

    python -m brdfz.gpu check FILE.brdfzrt [--backend wgpu|gl|webgl] [--pairs N]
    python -m brdfz.gpu export IN -o DIR --target glsl|essl|hlsl|wgsl|cuda|metal|slang [--repr SPEC]
"""

from .backend import BackendUnavailable
from .check import BACKENDS, TOLERANCE, backend, check
from .export import EXPORT_TARGETS, ExportError, export
from .layout import Layout
from .slang import SlangError, compile_entry
from .targets import TARGETS, emit

__all__ = ["BACKENDS", "TOLERANCE", "backend", "check", "Layout", "TARGETS", "SlangError", "compile_entry", "emit", "BackendUnavailable", "EXPORT_TARGETS",
           "ExportError", "export"]
