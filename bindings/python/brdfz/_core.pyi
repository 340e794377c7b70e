"""
brdfz: measured BRDFs, compactly stored (C++ core of the brdfz package)
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
import os
import typing
__all__: list[str] = ['Brdf', 'Candidate', 'ChannelMetrics', 'Compressed', 'FitReport', 'FitResult', 'FormatError', 'MAX_THREADS', 'Metrics', 'RECIPROCITY_THRESHOLD', 'Scene', 'Selection', 'Trial', 'UnsupportedError', 'ValidationCheck', 'ValidationReport', 'albedo', 'benchmark_specs', 'compress', 'compress_kinds', 'container_metadata', 'convert', 'default_candidates', 'directions', 'fit', 'format_of', 'formats', 'from_half_diff', 'is_reciprocal', 'keep_phi_d_whole', 'load', 'load_measurements', 'metric_samples', 'metrics', 'metrics_at', 'read_scene', 'reciprocity_error', 'representations', 'save', 'select_representation', 'simd', 'tabulate', 'to_half_diff', 'trial', 'validate']
class FormatError(ValueError):
    pass
class UnsupportedError(ValueError):
    pass
class Brdf:
    """
    A measured or compressed BRDF (brdf.h: normal +z, wi and wo pointing away)
    """
    def __repr__(self) -> str:
        ...
    def describe(self) -> str:
        """
        one line saying what this is
        """
    def eval(self, wi: numpy.typing.NDArray[numpy.floating], wo: numpy.typing.NDArray[numpy.floating]) -> numpy.typing.NDArray[numpy.float64]:
        """
        f_r (1/sr, no cosine) at direction pairs: wi, wo of shape (..., 3) (arrays, lists or tuples), broadcast over their leading dimensions -> (..., 3) float64 ((3,) for one pair)
        """
    def eval_cos(self, wi: numpy.typing.NDArray[numpy.floating], wo: numpy.typing.NDArray[numpy.floating]) -> numpy.typing.NDArray[numpy.float64]:
        """
        f_r·cosθi at direction pairs, broadcast as eval -> (..., 3) float64
        """
    def parts(self) -> dict | None:
        """
        the representation's stored arrays and parameters as a dict ('kind': tabular, compact, factored, pca or analytic), read-only; None for kinds without parts (RGL files, scattered measurements)
        """
    def pdf(self, wo: numpy.typing.NDArray[numpy.floating], wi: numpy.typing.NDArray[numpy.floating]) -> numpy.typing.NDArray[numpy.float64]:
        """
        density of sample(wo, ·) at wi per unit solid angle, broadcast as eval -> (...) (a scalar for one pair)
        """
    def sample(self, wo: numpy.typing.NDArray[numpy.floating], u: numpy.typing.NDArray[numpy.floating]) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
        """
        draws wi for each wo from u in [0, 1)^2 of shape (N, 2) (ValueError naming a row outside it) -> (wi (N, 3), pdf (N,), weight (N, 3)); weight = f·cosθi/pdf, failed samples have pdf 0 and weight 0
        """
    def sampler_parts(self) -> dict | None:
        """
        the tables of the sampler sample() and pdf() use ('kind': compact, halfvector or lobes), built with the representation; None for kinds without them
        """
    @property
    def channels(self) -> int:
        """
        1 (monochrome, repeated in r, g, b) or 3
        """
    @property
    def measured_theta_max(self) -> float:
        """
        the largest incident elevation (radians) up to which values are data, not extrapolation: below π/2 for RGL files (their θi range), π/2 otherwise
        """
    @property
    def nbytes(self) -> int:
        """
        exact size of the stored parameters in bytes
        """
    @property
    def parameters(self) -> dict[str, float] | None:
        """
        an analytic model's parameters by name; None otherwise
        """
    @property
    def table(self) -> numpy.typing.NDArray[numpy.float32] | None:
        """
        a table's values (θh, θd, φd, 3) float32, NaN where invalid; None otherwise
        """
class Compressed:
    """
    what compress() built and what it achieved
    """
    def __repr__(self) -> str:
        ...
    @property
    def brdf(self) -> Brdf:
        ...
    @property
    def build_seconds(self) -> float:
        """
        wall time of the build
        """
    @property
    def notes(self) -> list[str]:
        """
        what the builder wants the user to know (fit status, clamping)
        """
    @property
    def spec(self) -> str:
        """
        canonical spec text
        """
class ChannelMetrics:
    """
    one metric per channel and their mean
    """
    def __repr__(self) -> str:
        ...
    def to_dict(self) -> dict:
        ...
    @property
    def b(self) -> float:
        ...
    @property
    def g(self) -> float:
        ...
    @property
    def mean(self) -> float:
        ...
    @property
    def r(self) -> float:
        ...
class Metrics:
    """
    error metrics of an approximation against a reference (metrics.h)
    """
    def __repr__(self) -> str:
        ...
    def to_dict(self) -> dict:
        ...
    @property
    def cbrt_rmse(self) -> ChannelMetrics:
        ...
    @property
    def cos_rmse(self) -> ChannelMetrics:
        ...
    @property
    def cos_rmse_rel(self) -> ChannelMetrics:
        ...
    @property
    def log_rmse(self) -> ChannelMetrics:
        ...
    @property
    def negatives(self) -> int:
        """
        channel values below 0 (either BRDF), taken as 0 by every metric
        """
    @property
    def samples(self) -> int:
        """
        bins (or measurements) compared
        """
class FitReport:
    """
    how a fit went (fit/fit.h)
    """
    def __repr__(self) -> str:
        ...
    @property
    def at_bounds(self) -> list[str]:
        ...
    @property
    def best_start(self) -> int:
        ...
    @property
    def channel_cost(self) -> typing.Annotated[list[float], "FixedSize(3)"]:
        ...
    @property
    def excluded_cutoff(self) -> int:
        ...
    @property
    def excluded_invalid(self) -> int:
        ...
    @property
    def final_cost(self) -> float:
        ...
    @property
    def grid_bins(self) -> int:
        ...
    @property
    def initial_cost(self) -> float:
        ...
    @property
    def iterations(self) -> int:
        ...
    @property
    def loss(self) -> str:
        ...
    @property
    def message(self) -> str:
        ...
    @property
    def metrics(self) -> Metrics | None:
        """
        the model against the input, or None
        """
    @property
    def model(self) -> str:
        ...
    @property
    def poor_fit(self) -> bool:
        """
        whatever the status, the model misses the data (unexplained > 0.25 or cos_rmse_rel > 0.5)
        """
    @property
    def samples(self) -> int:
        ...
    @property
    def seconds(self) -> float:
        ...
    @property
    def start_costs(self) -> list[float]:
        ...
    @property
    def starts(self) -> int:
        ...
    @property
    def status(self) -> str:
        """
        converged, hit_bounds, no_convergence or insufficient_data
        """
    @property
    def termination(self) -> str:
        ...
    @property
    def total_iterations(self) -> int:
        ...
    @property
    def unexplained(self) -> float:
        ...
    @property
    def warnings(self) -> list[str]:
        ...
class FitResult:
    """
    a fitted model and its report
    """
    def __repr__(self) -> str:
        ...
    @property
    def brdf(self) -> Brdf:
        ...
    @property
    def report(self) -> FitReport:
        ...
class ValidationCheck:
    """
    one plausibility check (validate.h)
    """
    def __repr__(self) -> str:
        ...
    def to_dict(self) -> dict:
        ...
    @property
    def error(self) -> float | None:
        """
        reciprocity: the reciprocity error (cos_rmse_rel of f(wo, wi) against f(wi, wo) over directions); None for the other checks
        """
    @property
    def failed(self) -> int:
        ...
    @property
    def name(self) -> str:
        """
        non-negativity, reciprocity or energy
        """
    @property
    def ok(self) -> bool:
        ...
    @property
    def tested(self) -> int:
        ...
    @property
    def unit(self) -> str:
        """
        what was tested: bins, pairs or elevations
        """
    @property
    def worst(self) -> list:
        """
        the worst offences, worst first: angles in degrees and the values involved
        """
class ValidationReport:
    """
    the checks of validate(), in order
    """
    def __getitem__(self, arg0: str) -> ValidationCheck:
        ...
    def __repr__(self) -> str:
        ...
    def to_dict(self) -> dict:
        """
        as `brdfz validate --json` prints it, without the file name
        """
    @property
    def checks(self) -> list[ValidationCheck]:
        ...
    @property
    def ok(self) -> bool:
        ...
class Trial:
    """
    what one representation achieved against its source (select.h)
    """
    def __repr__(self) -> str:
        ...
    @property
    def brdf(self) -> Brdf:
        """
        the representation (None for a rejected candidate)
        """
    @property
    def build_seconds(self) -> float:
        ...
    @property
    def bytes(self) -> int:
        """
        Brdf.nbytes of the result
        """
    @property
    def describe(self) -> str:
        ...
    @property
    def eval_rate(self) -> float:
        """
        batch eval, pairs per second on one thread (0: not measured)
        """
    @property
    def metrics(self) -> Metrics:
        """
        the result against the source
        """
    @property
    def notes(self) -> list[str]:
        """
        from the builder (fit status, clamping)
        """
    @property
    def spec(self) -> str:
        """
        canonical spec text
        """
class Candidate(Trial):
    """
    one candidate of a selection and why it was kept or not
    """
    def __repr__(self) -> str:
        ...
    @property
    def accepted(self) -> bool:
        ...
    @property
    def error(self) -> float:
        """
        in the selection's metric; NaN when the candidate failed
        """
    @property
    def reason(self) -> str:
        """
        why it was rejected, or 'meets the budget'
        """
class Selection:
    """
    every candidate tried, cheapest first, and the one chosen
    """
    def __repr__(self) -> str:
        ...
    @property
    def brdf(self) -> Brdf:
        """
        the chosen representation, or None
        """
    @property
    def candidates(self) -> list[Candidate]:
        ...
    @property
    def chosen(self) -> int:
        """
        index into candidates; -1 when none met the budget
        """
class Scene:
    """
    the direction pairs a scene evaluates and their weights (scene.h)
    """
    @property
    def name(self) -> str:
        ...
    @property
    def samples(self) -> int:
        """
        direction pairs
        """
    @property
    def views(self) -> int:
        """
        views (pixels)
        """
def albedo(brdf: Brdf, theta_o: typing.Annotated[numpy.typing.ArrayLike, numpy.float64]) -> numpy.typing.NDArray[numpy.float64]:
    """
    directional albedo (quadrature, albedo.h) at θo in radians: shape of theta_o + (3,)
    """
def benchmark_specs() -> list[str]:
    """
    the settings the compression benchmark sweeps
    """
def compress(brdf: Brdf, spec: str, *, threads: typing.SupportsInt | typing.SupportsIndex = 0, progress: typing.Any = None) -> Compressed:
    """
    builds the representation SPEC names (as `brdfz compress`)
    """
def compress_kinds() -> list[str]:
    ...
def container_metadata(path: os.PathLike | str | bytes) -> dict:
    """
    a .brdfz file's provenance without reading its arrays: {'version', 'library_version', 'created', 'source' {'file', 'format', 'sha256'}, 'representation', 'spec', 'build_spec', 'achieved' {'lossless', 'nbytes', 'metrics' (against the source, or None)}}
    """
def convert(src: os.PathLike | str | bytes, dst: os.PathLike | str | bytes, *, res: tuple[typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex] | None = None, src_format: str = '', dst_format: str = '', lookup: str = 'linear', bin_position: str = 'centre', threads: typing.SupportsInt | typing.SupportsIndex = 0, progress: typing.Any = None) -> dict:
    """
    as `brdfz convert SRC DST`; returns the written bins' counts
    """
def default_candidates(source: Brdf = None, *, threads: typing.SupportsInt | typing.SupportsIndex = 0, directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> list[str]:
    """
    select_representation's candidates, cheapest first; for a source, with phi_d kept whole (keep_phi_d_whole) when it is not reciprocal (is_reciprocal)
    """
def directions(theta: numpy.typing.NDArray[numpy.floating], phi: numpy.typing.NDArray[numpy.floating]) -> numpy.typing.NDArray[numpy.float64]:
    """
    unit directions at polar angles theta (from the normal +z) and azimuths phi (from +x), radians, broadcast -> (..., 3)
    """
def fit(source: typing.Any, model: str, *, loss: str = 'log', starts: typing.SupportsInt | typing.SupportsIndex = 8, seed: typing.SupportsInt | typing.SupportsIndex = 1, robust: str = 'none', robust_scale: typing.SupportsFloat | typing.SupportsIndex = 0.1, max_theta: typing.SupportsFloat | typing.SupportsIndex = 80.0, samples: typing.SupportsInt | typing.SupportsIndex = 20000, max_seconds: typing.SupportsFloat | typing.SupportsIndex = 60.0, threads: typing.SupportsInt | typing.SupportsIndex = 0, progress: typing.Any = None) -> FitResult:
    """
    fits an analytic model (e.g. 'lambert+ggx') to a Brdf or a file, as `brdfz fit`
    """
def format_of(path: str) -> str:
    """
    the format name of a file's extension ('merl', 'rgl', ...)
    """
def formats() -> list:
    """
    the file formats, as `brdfz formats --json` lists them
    """
def from_half_diff(theta_h: numpy.typing.NDArray[numpy.floating], theta_d: numpy.typing.NDArray[numpy.floating], phi_d: numpy.typing.NDArray[numpy.floating], phi_h: numpy.typing.NDArray[numpy.floating] = 0.0) -> tuple:
    """
    direction pairs (wi, wo) at Rusinkiewicz angles (radians, broadcast), each (..., 3); to_half_diff's inverse
    """
def is_reciprocal(source: Brdf, *, threads: typing.SupportsInt | typing.SupportsIndex = 0, directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> bool:
    """
    whether the source's reciprocity error is at most RECIPROCITY_THRESHOLD
    """
def keep_phi_d_whole(specs: collections.abc.Sequence[str]) -> list[str]:
    """
    the specs with symmetry=bilateral where they would fold phi_d by reciprocity (tabular, svd, nmf)
    """
def load(path: os.PathLike | str | bytes, *, lookup: str = 'linear', bin_position: str = 'centre', format: str = '') -> Brdf:
    """
    a BRDF file (.binary, .bsdf, .brdfz, .exr, .json; format overrides the extension)
    """
def load_measurements(path: os.PathLike | str | bytes) -> dict:
    """
    scattered measurements (Cornell .brdf, ALTA .dat): {'wi', 'wo' (N, 3) unit directions, 'f' (N, 3) f_r, 'channels', 'source'}; UnsupportedError for a file holding a BRDF (load it)
    """
def metric_samples(reference: Brdf, *, max_theta: typing.SupportsFloat | typing.SupportsIndex = 80.0, threads: typing.SupportsInt | typing.SupportsIndex = 0, over: str = 'grid', directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> tuple[numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64], numpy.typing.NDArray[numpy.float64]]:
    """
    (wi, wo, f_reference): the samples metrics() takes against reference
    """
def metrics(reference: typing.Any, approx: Brdf, *, max_theta: typing.SupportsFloat | typing.SupportsIndex = 80.0, threads: typing.SupportsInt | typing.SupportsIndex = 0, over: str = 'grid', directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> Metrics:
    """
    metrics of approx against reference (a Brdf, or a file: a BRDF or Cornell/ALTA measurements)
    """
def metrics_at(wi: typing.Any, reference: typing.Any, approx: typing.Any) -> Metrics:
    """
    the metrics of approx against reference values (N, 3) at pairs whose incident directions are wi
    """
def read_scene(path: os.PathLike | str | bytes) -> Scene:
    """
    a scene file (docs/scene-json.md), its samples drawn
    """
def reciprocity_error(brdf: Brdf, *, max_theta: typing.SupportsFloat | typing.SupportsIndex = 80.0, threads: typing.SupportsInt | typing.SupportsIndex = 0, directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1) -> Metrics:
    """
    metrics of f(wo, wi) against f(wi, wo) over direction pairs (cos_rmse_rel.mean: the reciprocity error)
    """
def representations() -> list:
    """
    the representation kinds compress() builds, as `brdfz representations --json` lists them
    """
def save(brdf: Brdf, path: os.PathLike | str | bytes, *, res: tuple[typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex] | None = None, format: str = '', threads: typing.SupportsInt | typing.SupportsIndex = 0, progress: typing.Any = None, build_spec: str = '', source: os.PathLike | str | bytes | None = None, source_metrics: typing.Any = None) -> dict:
    """
    writes atomically (format from the extension unless given); returns the written bins' counts. .brdfz keeps provenance: build_spec (the compress() spec), source (the file it came from: name, format and SHA-256) and source_metrics (its metrics against that file)
    """
def select_representation(brdf: Brdf, max_error: typing.SupportsFloat | typing.SupportsIndex | None = None, *, max_bytes: typing.SupportsInt | typing.SupportsIndex | None = None, metric: str = 'log', scene: Scene | None = None, candidates: collections.abc.Sequence[str] = [], measure_speed: bool = True, threads: typing.SupportsInt | typing.SupportsIndex = 0, over: str = 'directions', directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1, on_candidate: typing.Any = None) -> Selection:
    """
    by budget (select.h): the smallest candidate within max_error, the most accurate within max_bytes, or the smallest within both; on_candidate(candidate, index, total) after each
    """
def simd() -> str:
    """
    the instruction set Brdf's batch calls run with on this CPU: 'avx512', 'avx2' or 'sse2' (x86-64, chosen at import), 'neon' (ARM64)
    """
def tabulate(brdf: Brdf, res: tuple[typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex] = (90, 90, 180), *, lookup: str = 'linear', negative: str = 'clamp', symmetry: str = 'reciprocal', threads: typing.SupportsInt | typing.SupportsIndex = 0, progress: typing.Any = None) -> Brdf:
    """
    the Brdf evaluated on a (θh, θd, φd) Rusinkiewicz grid at bin centres, as a table (symmetry: table.h)
    """
def to_half_diff(wi: numpy.typing.NDArray[numpy.floating], wo: numpy.typing.NDArray[numpy.floating]) -> tuple:
    """
    Rusinkiewicz angles of direction pairs (coords.h), broadcast as Brdf.eval -> (theta_h, phi_h, theta_d, phi_d), radians, each of the leading shape
    """
def trial(brdf: Brdf, spec: str, *, measure_speed: bool = True, max_theta: typing.SupportsFloat | typing.SupportsIndex = 80.0, threads: typing.SupportsInt | typing.SupportsIndex = 0, over: str = 'grid', directions: typing.SupportsInt | typing.SupportsIndex = 262144, seed: typing.SupportsInt | typing.SupportsIndex = 1, progress: typing.Any = None) -> Trial:
    """
    compress(brdf, spec) and measure it: bytes, metrics, eval speed, build time
    """
def validate(brdf: Brdf, *, res: tuple[typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex, typing.SupportsInt | typing.SupportsIndex] = (90, 90, 180), theta: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex] = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0], rtol: typing.SupportsFloat | typing.SupportsIndex = 0.05, atol: typing.SupportsFloat | typing.SupportsIndex = 0.001, albedo_tol: typing.SupportsFloat | typing.SupportsIndex = 0.01) -> ValidationReport:
    """
    non-negativity (a table's values, else f on the res grid), reciprocity (rtol, atol in 1/sr) and energy (reflectance <= 1 + albedo_tol at the elevations theta, degrees), as `brdfz validate`
    """
MAX_THREADS: int = 1024
RECIPROCITY_THRESHOLD: float = 0.01
__version__: str = '0.1.0'
