"""brdfz: measured BRDFs, compactly stored.

Every measured or compressed BRDF is a :class:`Brdf`. Directions follow brdf.h: the normal is +z,
``wi`` (incident light) and ``wo`` (outgoing) both point away from the surface; ``eval`` returns
f_r without the cosine, ``eval_cos`` f_r·cosθi. Arrays are numpy arrays of shape (N, 3) (``u``:
(N, 2)), float32 or float64; results are float64. Rows are normalised as the ``brdfz`` command
normalises them; a zero or non-finite row is a ValueError.

Errors: library errors keep their message and arrive as ValueError (bad arguments),
:class:`FormatError` and :class:`UnsupportedError` (both ValueError subclasses: bad or unhandled
files), OSError (FileNotFoundError when the file read does not exist).

Long operations (compress, fit, tabulate, save, convert) take ``progress``: True prints
"label NN%" on stderr, a callable receives the fraction done (0..1] (from a worker thread, holding
the GIL). They release the GIL while they work, as do Brdf.eval / eval_cos / pdf / sample.
"""
from __future__ import annotations

import os
import sys
from typing import Callable, Optional, Tuple, Union

from . import _core
from ._core import (
    Brdf,
    ChannelMetrics,
    Compressed,
    FitReport,
    FitResult,
    FormatError,
    Metrics,
    UnsupportedError,
    albedo,
    compress_kinds,
    load,
)

__all__ = [
    "Brdf", "ChannelMetrics", "Compressed", "FitReport", "FitResult", "FormatError", "Metrics",
    "UnsupportedError", "albedo", "compress", "compress_kinds", "convert", "fit", "load", "metrics",
    "save", "tabulate",
]

Path = Union[str, os.PathLike]
Progress = Union[bool, Callable[[float], object], None]
Resolution = Tuple[int, int, int]


class _StderrBar:
    """"label NN%" on stderr, rewritten in place; a new line at 100%."""

    def __init__(self, label: str):
        self.label = label
        self.last = -1

    def __call__(self, fraction: float) -> None:
        pct = int(fraction * 100)
        if pct == self.last:
            return
        self.last = pct
        sys.stderr.write(f"\r{self.label} {pct}%" + ("\n" if pct >= 100 else ""))
        sys.stderr.flush()


def _hook(progress: Progress, label: str) -> Optional[Callable[[float], object]]:
    if progress is None or progress is False:
        return None
    if progress is True:
        return _StderrBar(label)
    if callable(progress):
        return progress
    raise ValueError("progress must be True, False, None or a callable taking the fraction done")


def save(brdf: Brdf, path: Path, *, res: Optional[Resolution] = None, format: str = "", threads: int = 0,
         progress: Progress = None) -> dict:
    """Writes `brdf` atomically (format from the extension unless `format` names one). A format that
    stores tables tabulates other representations on `res` (default: the table's own grid, or
    90x90x180). Returns the written bins' validity counts."""
    return _core.save(brdf, path, res=res, format=format, threads=threads, progress=_hook(progress, "tabulating"))


def convert(src: Path, dst: Path, *, res: Optional[Resolution] = None, src_format: str = "", dst_format: str = "",
            lookup: str = "linear", bin_position: str = "centre", threads: int = 0, progress: Progress = None) -> dict:
    """As ``brdfz convert SRC DST``: load, tabulate where the output format needs it, write atomically."""
    return _core.convert(src, dst, res=res, src_format=src_format, dst_format=dst_format, lookup=lookup,
                         bin_position=bin_position, threads=threads, progress=_hook(progress, "tabulating"))


def compress(brdf: Brdf, spec: str, *, report: bool = False, threads: int = 0, progress: Progress = None):
    """Builds the representation `spec` names, as ``brdfz compress`` spells it ("tabular:res=45x45x90",
    "analytic:lambert+ggx", "svd:rank=4", ...; see compress_kinds()). Returns the Brdf, or with
    report=True a :class:`Compressed` holding it with its canonical spec, build_seconds and notes."""
    built = _core.compress(brdf, spec, threads=threads, progress=_hook(progress, "compressing"))
    return built if report else built.brdf


def fit(source: Union[Brdf, Path], model: str, *, loss: str = "log", starts: int = 8, seed: int = 1,
        robust: str = "none", robust_scale: float = 0.1, max_theta: float = 80.0, samples: int = 20000,
        max_seconds: float = 60.0, threads: int = 0, progress: Progress = None) -> FitResult:
    """Fits an analytic model ("lambert+ggx", lobes joined by '+') to a Brdf or a file (a BRDF, or
    Cornell / ALTA measurements), with the options of ``brdfz fit``. The result holds the model as a
    Brdf (``.brdf``, its ``parameters`` by name) and the report (``.report.status``, ``.message``,
    ``.metrics``, ...); check the status before trusting the model."""
    return _core.fit(source, model, loss=loss, starts=starts, seed=seed, robust=robust, robust_scale=robust_scale,
                     max_theta=max_theta, samples=samples, max_seconds=max_seconds, threads=threads,
                     progress=_hook(progress, "fitting"))


def metrics(reference: Union[Brdf, Path], approx: Brdf, *, max_theta: float = 80.0, threads: int = 0) -> Metrics:
    """cos_rmse, cos_rmse_rel, log_rmse and cbrt_rmse of `approx` against `reference` (a Brdf, or a
    file: a BRDF or Cornell / ALTA measurements), as ``brdfz diff``."""
    return _core.metrics(reference, approx, max_theta=max_theta, threads=threads)


def tabulate(brdf: Brdf, res: Resolution = (90, 90, 180), *, lookup: str = "linear", negative: str = "clamp",
             threads: int = 0, progress: Progress = None) -> Brdf:
    """`brdf` evaluated at the bin centres of a (θh, θd, φd) Rusinkiewicz grid, as a table Brdf
    (its values: ``.table``). Negative values are clamped to 0 or, with negative="invalidate",
    marked invalid."""
    return _core.tabulate(brdf, res, lookup=lookup, negative=negative, threads=threads,
                          progress=_hook(progress, "tabulating"))
