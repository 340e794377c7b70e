"""brdfz on the GPU: the shaders of bindings/gpu/shaders (one Slang source, translated to each shading
language by the Slang compiler) and their check against the C++ library on software or real GPUs.

    python -m brdfz.gpu check FILE.brdfzrt [--backend wgpu] [--pairs N]
"""

from .check import TOLERANCE, backend, check
from .layout import Layout
from .slang import TARGETS, SlangError, compile_entry
from .wgpu_backend import BackendUnavailable

__all__ = ["TOLERANCE", "backend", "check", "Layout", "TARGETS", "SlangError", "compile_entry", "BackendUnavailable"]
