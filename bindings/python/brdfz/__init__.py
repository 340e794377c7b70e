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
the GIL). They release the GIL while they work, as do Brdf.eval / eval_cos / pdf / sample. A
progress callable that raises stops the operation at that call, and Ctrl-C (KeyboardInterrupt, or
any signal handler's exception) stops compress, trial, fit, metrics, tabulate, save and convert
within a few hundredths of a second; the exception is raised and no output file is written.
``threads`` (0: one per hardware thread) is at most MAX_THREADS (1024); more is a ValueError.
"""
from __future__ import annotations

import json
import math
import os
import sys
import tempfile
from typing import Callable, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import MAX_THREADS, RECIPROCITY_THRESHOLD, __version__
from ._core import (
    Brdf,
    Candidate,
    ChannelMetrics,
    Compressed,
    FitReport,
    FitResult,
    FormatError,
    Metrics,
    Scene,
    Selection,
    Trial,
    UnsupportedError,
    ValidationCheck,
    ValidationReport,
    albedo,
    benchmark_specs,
    compress_kinds,
    container_metadata,
    default_candidates,
    directions,
    format_of,
    formats,
    from_half_diff,
    is_reciprocal,
    keep_phi_d_whole,
    load,
    representations,
    simd,
    to_half_diff,
    validate,
)

__all__ = [
    "Brdf", "Candidate", "ChannelMetrics", "Compressed", "FitReport", "FitResult", "FormatError", "MAX_THREADS",
    "Metrics", "RECIPROCITY_THRESHOLD", "Scene", "Selection", "Trial", "UnsupportedError", "ValidationCheck",
    "ValidationReport", "albedo",
    "benchmark_specs", "compress", "compress_kinds", "container_metadata", "convert", "default_candidates", "directions", "export", "fit",
    "format_of", "formats", "from_half_diff", "is_reciprocal", "keep_phi_d_whole",
    "load", "load_measurements", "Measurements", "metric_samples", "metrics", "metrics_at", "read_scene", "reciprocity_error", "representations", "save",
    "simd", "tabulate", "to_half_diff", "trial", "validate",
]

Path = Union[str, os.PathLike]
Progress = Union[bool, Callable[[float], object], None]
Resolution = Tuple[int, int, int]


class Measurements(NamedTuple):
    """Scattered measurements (Cornell .brdf, ALTA .dat) as load_measurements() reads them: f_r (1/sr,
    no cosine) at direction pairs, in brdf.h's frame."""
    wi: np.ndarray  # (N, 3) unit incident directions
    wo: np.ndarray  # (N, 3) unit outgoing directions
    f: np.ndarray  # (N, 3) f_r; a monochrome source repeats its value in the three channels
    channels: int  # 1 or 3
    source: str  # where the samples came from


def load_measurements(path: Path) -> Measurements:
    """The measurements of a Cornell .brdf or ALTA .dat file, as fit() and metrics() read them
    (brdfz.UnsupportedError for a file holding a BRDF: load() it)."""
    return Measurements(**_core.load_measurements(path))


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
         progress: Progress = None, build_spec: str = "", source: Optional[Path] = None,
         source_metrics: Optional[Metrics] = None) -> dict:
    """Writes `brdf` atomically (format from the extension unless `format` names one). A format that
    stores tables tabulates other representations on `res` (default: the table's own grid, or
    90x90x180). A .brdfz file keeps provenance as ``brdfz compress`` writes it: `build_spec` (the
    compress() spec that built `brdf`), `source` (the file it was built from: its name, format and
    SHA-256) and `source_metrics` (its metrics against that file). Returns the written bins' validity
    counts."""
    return _core.save(brdf, path, res=res, format=format, threads=threads, progress=_hook(progress, "tabulating"),
                      build_spec=build_spec, source=source, source_metrics=source_metrics)


def convert(src: Path, dst: Path, *, res: Optional[Resolution] = None, src_format: str = "", dst_format: str = "",
            lookup: str = "linear", bin_position: str = "centre", threads: int = 0, progress: Progress = None) -> dict:
    """As ``brdfz convert SRC DST``: load, tabulate where the output format needs it, write atomically."""
    return _core.convert(src, dst, res=res, src_format=src_format, dst_format=dst_format, lookup=lookup,
                         bin_position=bin_position, threads=threads, progress=_hook(progress, "tabulating"))


def export(source: Union[Brdf, Path], path: Path, *, repr: Optional[str] = None, threads: int = 0,
           progress: Progress = None) -> dict:
    """As ``brdfz export``: the runtime layout (.brdfzrt, formats/SPEC.md §6) of `source` (a Brdf or a
    file), or of its `repr` representation (a compress() spec), written atomically: the arrays and the
    compact sampler brdfz::runtime and GPUs read. Returns the path, its bytes and what it holds."""
    brdf = source if isinstance(source, Brdf) else load(source)
    if repr:
        brdf = compress(brdf, repr, threads=threads, progress=progress)
    save(brdf, path, format="brdfzrt")
    return {"path": os.fspath(path), "bytes": os.path.getsize(path), "describe": brdf.describe()}


def read_scene(source: Union[Path, Mapping, Scene]) -> Scene:
    """A scene for error budgets (docs/scene-json.md): a scene file, or a dict with the file's schema
    ("format" and "version" may be left out). Bad members are ValueErrors naming them."""
    if isinstance(source, Scene):
        return source
    if not isinstance(source, Mapping):
        return _core.read_scene(source)
    doc = {"format": "brdfz-scene", "version": 1, **_json_values(source, "")}
    # One schema, one reader: the dict goes through the C++ scene file reader.
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "scene.json")
        with open(path, "w") as f:
            json.dump(doc, f, allow_nan=False)
        try:
            return _core.read_scene(path)
        except ValueError as e:
            raise type(e)(str(e).replace(path, "scene dict")) from None


def _json_values(value, where: str):
    """A scene dict's values as JSON has them: numpy scalars and arrays as numbers and lists; a number
    that is not finite, or a value JSON cannot hold, is a ValueError naming its member."""
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        value = value.tolist()
    if isinstance(value, Mapping):
        return {str(k): _json_values(v, f"{where}.{k}" if where else str(k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_values(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"scene dict: {where}: {value} is not a finite number")
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise ValueError(f"scene dict: {where}: a value of type {type(value).__name__} is not JSON")


def trial(brdf: Brdf, spec: str, *, measure_speed: bool = True, max_theta: float = 80.0, threads: int = 0,
          over: str = "grid", directions: int = 1 << 18, seed: int = 1, progress: Progress = None) -> Trial:
    """compress(brdf, spec) and measure what it achieved, as ``brdfz compress`` reports it: bytes,
    metrics against `brdf` (over its grid or over direction pairs: see metrics()), eval_rate (pairs/s,
    one thread) and build_seconds."""
    return _core.trial(brdf, spec, measure_speed=measure_speed, max_theta=max_theta, threads=threads, over=over,
                       directions=directions, seed=seed, progress=_hook(progress, "compressing"))


def _candidate_hook(progress: Progress, done_on_accept: bool = True) -> Optional[Callable[[Candidate, int, int], object]]:
    if progress is None or progress is False:
        return None
    if progress is True:
        def line(c: Candidate, index: int, total: int) -> None:
            sys.stderr.write(f"  [{index + 1}/{total}] {c.spec:34} {c.bytes:>10} B  error {c.error:<10.4g} "
                             f"{c.eval_rate:9.3g} pairs/s {c.build_seconds:7.2f} s  {c.reason}\n")
            sys.stderr.flush()
        return line
    if callable(progress):
        # An accepted candidate ends the search only under an error budget; under a size budget alone it
        # is the best so far.
        return lambda c, index, total: progress(1.0 if c.accepted and done_on_accept else (index + 1) / total)
    raise ValueError("progress must be True, False, None or a callable taking the fraction done")


def compress(brdf: Brdf, spec: Optional[str] = None, *, auto: bool = False, max_error: Optional[float] = None,
             max_bytes: Optional[int] = None, metric: str = "log", scene: Union[Path, Mapping, Scene, None] = None,
             candidates: Optional[Sequence[str]] = None, over: str = "directions", directions: int = 1 << 18,
             seed: int = 1, report: bool = False, threads: int = 0, progress: Progress = None):
    """Builds the representation `spec` names, as ``brdfz compress`` spells it ("tabular:res=45x45x90",
    "analytic:lambert+ggx", "svd:rank=4", ...; see compress_kinds()). Returns the Brdf, or with
    report=True a :class:`Compressed` holding it with its canonical spec, build_seconds and notes.

    With auto=True (``brdfz compress --auto``) it tries `candidates` (default: default_candidates(brdf),
    with φd kept whole when `brdf`'s reciprocity error is above RECIPROCITY_THRESHOLD) from cheapest to
    richest and returns the first, so the smallest, whose error in `metric` ("log": log_rmse, "cos":
    cos_rmse_rel, "image": relative pixel RMSE; under `scene` when given, a scene file or dict) is at
    most `max_error`, the errors without a scene taken `over` direction pairs (the default, as a
    renderer sees them) or over="grid" (as in metrics()). With `max_bytes` (``--max-bytes``) alone it returns the most
    accurate candidate of at most that many bytes; with both, the smallest within both. report=True returns the :class:`Selection` instead, every
    candidate with its bytes, error, eval_rate, build_seconds and why it was rejected. No candidate
    within the budget is a ValueError (its ``selection`` attribute holds the report). progress=True
    prints a line per candidate."""
    if not auto:
        if spec is None:
            raise ValueError("compress: give a spec, or auto=True with max_error, max_bytes or both")
        built = _core.compress(brdf, spec, threads=threads, progress=_hook(progress, "compressing"))
        return built if report else built.brdf
    if spec is not None:
        raise ValueError("compress: give a spec or auto=True, not both")
    if max_error is None and max_bytes is None:
        raise ValueError("compress(auto=True): give max_error, max_bytes or both")
    if max_error is not None and not (math.isfinite(max_error) and max_error > 0):
        raise ValueError("compress(auto=True): max_error must be a finite number > 0")
    if max_bytes is not None and not (isinstance(max_bytes, int) and max_bytes >= 1):
        raise ValueError(f"compress(auto=True): max_bytes must be an integer >= 1, not {max_bytes!r}")
    selection = _core.select_representation(
        brdf, max_error, max_bytes=max_bytes, metric=metric, scene=None if scene is None else read_scene(scene),
        candidates=list(candidates or []), threads=threads, over=over, directions=directions, seed=seed,
        on_candidate=_candidate_hook(progress, done_on_accept=max_error is not None))
    if selection.chosen < 0:
        tried = "; ".join(f"{c.spec}: {c.reason}" for c in selection.candidates)
        budget = ", ".join(([f"{max_error:g} in {metric}"] if max_error is not None else []) +
                           ([f"{max_bytes} bytes"] if max_bytes is not None else []))
        error = ValueError(f"compress(auto=True): no candidate meets the budget {budget} ({tried})")
        error.selection = selection
        raise error
    return selection if report else selection.brdf


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


def metrics(reference: Union[Brdf, Path], approx: Brdf, *, max_theta: float = 80.0, threads: int = 0,
            over: str = "grid", directions: int = 1 << 18, seed: int = 1) -> Metrics:
    """cos_rmse, cos_rmse_rel, log_rmse and cbrt_rmse of `approx` against `reference` (a Brdf, or a
    file: a BRDF or Cornell / ALTA measurements), as ``brdfz diff``.

    over="grid": each bin of the reference's Rusinkiewicz grid once (its own grid for a table,
    otherwise 90x90x180 at bin starts), θi and θo below `max_theta` (degrees) and within the
    reference's measured range. over="directions": `directions` pairs drawn from `seed`, wi and wo
    uniform in solid angle (θi below `max_theta` and within the measured range, θo below `max_theta`,
    every azimuth), each pair once: the error a renderer sees. Measurements are judged at their own
    points (over="grid" only)."""
    return _core.metrics(reference, approx, max_theta=max_theta, threads=threads, over=over, directions=directions,
                         seed=seed)


def metric_samples(reference: Brdf, *, over: str = "grid", max_theta: float = 80.0, directions: int = 1 << 18,
                   seed: int = 1, threads: int = 0):
    """(wi, wo, f): the direction pairs metrics() judges against `reference` with these options, and
    the reference's f_r there ((N, 3) float64 arrays; over the grid, a table's stored values). With
    metrics_at(), judges what is not a Brdf (a peer's network) on exactly those samples."""
    return _core.metric_samples(reference, max_theta=max_theta, threads=threads, over=over, directions=directions,
                                seed=seed)


def reciprocity_error(brdf: Brdf, *, max_theta: float = 80.0, directions: int = 1 << 18, seed: int = 1,
                      threads: int = 0) -> Metrics:
    """The metrics of f(wo, wi) against f(wi, wo) over `directions` pairs uniform in solid angle, both
    elevations below `max_theta` and within the measured range; ``.cos_rmse_rel.mean`` is the number
    ``brdfz info`` reports (0 for a reciprocal table, 0.1-1 for real RGL files)."""
    return _core.reciprocity_error(brdf, max_theta=max_theta, directions=directions, seed=seed, threads=threads)


def metrics_at(wi, reference, approx) -> Metrics:
    """The metrics of `approx` against `reference`, (N, 3) arrays of f_r at pairs whose incident
    directions are the rows of `wi` (cosθi = wi[:, 2]); as metrics() computes them from its samples."""
    return _core.metrics_at(wi, reference, approx)


def tabulate(brdf: Brdf, res: Resolution = (90, 90, 180), *, lookup: str = "linear", negative: str = "clamp",
             symmetry: str = "reciprocal", threads: int = 0, progress: Progress = None) -> Brdf:
    """`brdf` evaluated at the bin centres of a (θh, θd, φd) Rusinkiewicz grid, as a table Brdf
    (its values: ``.table``). Negative values are clamped to 0 or, with negative="invalidate",
    marked invalid. symmetry="reciprocal" folds φd over [0, π) (a bin holds the mean of f(wi, wo)
    and f(wo, wi)); "none" keeps φd over [0, 2π); "bilateral" folds |φd| over [0, π] by the mirror
    y → −y (a bin holds the mean of f at the pair and its mirror image, f(wi, wo) and f(wo, wi) apart)."""
    return _core.tabulate(brdf, res, lookup=lookup, negative=negative, symmetry=symmetry, threads=threads,
                          progress=_hook(progress, "tabulating"))
