"""Whole databases on Dask: every setting on every material, one task per (material, spec).

    python -m brdfz.batch MATERIAL_OR_DIR... --specs SPEC... --out DIR [--workers N | --scheduler ADDR]
                          [--over directions|grid] [--budgets E...] [--force] [--retries N]
                          [--threads T] [--memory-per-worker BYTES] [--render-size N] [--no-charts]

Each task loads its material, builds the representation and measures it against the material
(brdfz.trial: what `brdfz compress` reports; the errors are over direction pairs uniform in solid
angle, what a renderer sees, or with --over grid over the bins of the material's grid), then writes it atomically as DIR/<material>/<spec-hash>.brdfz (the spec
in the file's build_spec, the material's name, format and SHA-256 as its source) and its catalogue row
as <spec-hash>.json beside it, the record a rerun trusts. DIR/catalogue.csv (and catalogue.parquet
when pyarrow is installed) has one row per task (COLUMNS), status "ok" or "failed" with the one-line
error; it is rewritten atomically as tasks finish, so an interrupted batch leaves a valid catalogue of
what finished. At the end: the charts of python -m brdfz.bench over the whole catalogue (per-material
Pareto fronts; the smallest setting within each --budgets cos_rmse_rel) and DIR/summary.md, judged by
the errors over directions wherever they were measured (brdfz.report.error_column).

A rerun skips the tasks whose record exists, whose output is still the file the task wrote (its
SHA-256) and whose input file hash, spec, brdfz version and --over are unchanged, reusing their rows
(--force rebuilds). Specs are compared as normalise_spec() writes them, so spellings of one setting
are one task. Ctrl-C stops this machine's workers before the catalogue is written, so that it lists
every task with a record; a cluster that cannot be reached, or --workers N without Dask, is an error
before anything is written. A corrupt material fails its own tasks only. A task whose worker dies is
run again on another (Dask's scheduler, up to its distributed.scheduler.allowed-failures); a task that
raises something other than a bad-input error (MemoryError, a missing module on a worker) is retried
--retries times.

Workers: --workers N starts a Dask LocalCluster of N single-threaded worker processes (default: one per
CPU), each declaring its share of the memory as the resource MEMORY; each task declares its estimated
peak (estimate_memory), so a worker never runs more tasks than its memory holds. --scheduler ADDR uses
an existing cluster (dask-jobqueue, Kubernetes, Coiled...; start its workers with
`--resources MEMORY=BYTES` for the same protection). --workers 1 runs the tasks here, one after the
other, without Dask. Exit status 1 when a task failed (the catalogue says which and why).
"""
from __future__ import annotations

import argparse
import datetime
import functools
import glob
import hashlib
import inspect
import json
import math
import os
import pathlib
import signal
import sys
import time
import uuid
from dataclasses import dataclass
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import brdfz
from brdfz import report

Row = Dict[str, Any]
PathLike = Union[str, os.PathLike]

METRICS = ["cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"]
COLUMNS = ["material", "spec", "status", "bytes", *METRICS, "eval_rate", "build_seconds", "output", "error",
           "over", "build_spec", "describe", "notes", "format", "input", "input_bytes", "input_sha256", "ratio",
           "file_bytes", "load_seconds", "measure_seconds", "write_seconds", "cpu_seconds", "worker", "started",
           "brdfz_version"]
OVERS = ("grid", "directions")
# What folders are searched for: the BRDF files brdfz.load reads.
BRDF_SUFFIXES = (".binary", ".bsdf", ".brdfz", ".exr")
DEFAULT_BUDGETS = report.DEFAULT_BUDGETS


def columns(overs: Sequence[str]) -> List[str]:
    """The catalogue's columns: COLUMNS, then <over>_<metric> for each further `overs` entry."""
    return COLUMNS + [f"{o}_{m}" for o in overs[1:] for m in METRICS]


# ---------------------------------------------------------------------------------------------- inputs

def material_files(names: Sequence[PathLike]) -> List[pathlib.Path]:
    """Files named, and the BRDF files (BRDF_SUFFIXES) inside folders named."""
    out = []
    for name in names:
        p = pathlib.Path(name)
        if p.is_dir():
            out += sorted(f for f in p.iterdir() if f.suffix in BRDF_SUFFIXES and f.is_file())
        elif p.exists():
            out.append(p)
        else:
            raise FileNotFoundError(f"{name}: no such file or folder")
    return out


# What a batch writes at the top of its output folder, beside the materials' folders.
_OWN_NAMES = {"catalogue.csv", "catalogue.parquet", "summary.md", "renders"}


def material_names(files: Sequence[pathlib.Path]) -> Dict[str, pathlib.Path]:
    """name (the file's stem) -> file; two files with one name are an error, as their outputs would clash,
    and so is a name that is not a folder of its own inside the output folder ("..", "catalogue.csv")."""
    out: Dict[str, pathlib.Path] = {}
    for f in files:
        if f.stem in ("", ".", "..") or f.stem in _OWN_NAMES:
            raise ValueError(f"{f}: the material name {f.stem!r} cannot be its folder in the output folder; "
                             "rename the file")
        if f.stem in out and out[f.stem].resolve() != f.resolve():
            raise ValueError(f"two materials named {f.stem}: {out[f.stem]} and {f}")
        out[f.stem] = f
    return out


@functools.lru_cache(maxsize=None)
def _defaults() -> Dict[str, Dict[str, str]]:
    """kind -> {key: default} for the keys whose default is a plain value (not "(the source's ...)")."""
    return {k["kind"]: {key["name"]: key["default"] for key in k["keys"]
                        if key["default"] and not any(c in key["default"] for c in " ()")}
            for k in brdfz.representations()}


def _value(text: str) -> str:
    """A spec value as one spelling: sizes without leading zeros ("08x8x16" is "8x8x16"), numbers as
    numbers ("0.50" is "0.5", "0.0" is "0"); other text (words, file names) as it is."""
    parts = text.split("x")
    if all(p.isdigit() for p in parts):
        return "x".join(str(int(p)) for p in parts)
    if not all(c in "0123456789+-.eE" for c in text):
        return text
    try:
        number = float(text)
    except ValueError:
        return text
    if not math.isfinite(number):
        return text
    return str(int(number)) if number.is_integer() else repr(number)


def normalise_spec(spec: str) -> str:
    """One text for specs that build the same thing: options in key order, values in one spelling
    (_value), options that give their kind's default left out ("tabular:phih=1,res=08x8x16" and
    "tabular:res=8x8x16"). A spec that does not parse is returned as it is, for the build to refuse."""
    kind, colon, rest = spec.strip().partition(":")
    if not colon:
        return kind
    positional, options = [], {}
    for part in rest.split(","):
        key, eq, value = part.partition("=")
        if not eq:
            positional.append(part)
        elif key in options:
            return spec
        else:
            options[key] = _value(value)
    defaults = _defaults().get(kind, {})
    kept = [f"{k}={v}" for k, v in sorted(options.items()) if k not in defaults or _value(defaults[k]) != v]
    return kind + (":" + ",".join(positional + kept) if positional or kept else "")


def spec_hash(spec: str) -> str:
    """The output name of a spec: 16 hex digits of the SHA-256 of its normalise_spec() text, so that
    equivalent spellings name one output."""
    return hashlib.sha256(normalise_spec(spec).encode()).hexdigest()[:16]


def file_sha256(path: PathLike) -> str:
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _integers(text: str, default: List[int]) -> List[int]:
    try:
        return [int(v) for v in text.split("x")] if text else default
    except ValueError:
        return default


def estimate_memory(input_bytes: int, spec: str) -> int:
    """A task's peak memory in bytes above a worker's baseline, from its input file's size and the grid
    its spec builds on (res=, else MERL's 90x90x180; bivariate: × phi), with the sample points of an
    lsq fit or filter (ss³ per bin). An upper bound of the peaks measured on the shared RGL files and
    MERL tables (bench/README.md, "brdfz.batch at scale"), with room for larger inputs."""
    kind, _, options = spec.partition(":")
    opts = dict(o.split("=", 1) for o in options.split(",") if "=" in o)
    dims = _integers(opts.get("res", ""), [90, 90, 180])
    bins = 1
    for d in dims:
        bins *= max(d, 1)
    if kind == "bivariate" and len(dims) == 2:
        bins *= _integers(opts.get("phi", ""), [180])[0]
    peak = 64e6 + input_bytes + 100 * bins
    if "lsq" in (opts.get("fit"), opts.get("filter")):
        ss = _integers(opts.get("ss", ""), [2 if kind in ("svd", "nmf") else 3])[0]
        peak += 400 * bins * ss ** 3
    return int(peak)


# ----------------------------------------------------------------------------------------------- tasks

def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _one_line(e: BaseException) -> str:
    text = " ".join(str(e).split()) or type(e).__name__
    return text if isinstance(e, (ValueError, OSError)) else f"{type(e).__name__}: {text}"


def _worker() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"


def _write_json(path: pathlib.Path, doc: Any) -> None:
    report.atomic_write(path, lambda f: json.dump(doc, f, indent=1))


def _paths(out_dir: PathLike, material: str, spec: str) -> Tuple[pathlib.Path, pathlib.Path]:
    output = pathlib.Path(out_dir) / material / f"{spec_hash(spec)}.brdfz"
    return output, output.with_suffix(".json")


def build_task(material: str, path: str, spec: str, out_dir: str, overs: Sequence[str], threads: int,
               fingerprint: Dict[str, Any]) -> Row:
    """One (material, spec) task, run on a worker: load, build, measure, write; returns its catalogue
    row. A failure (a corrupt file, a bad spec, a write that fails) is a failed row with its one-line
    error; MemoryError propagates, for Dask to retry the task."""
    output, record = _paths(out_dir, material, spec)
    row: Row = dict.fromkeys(columns(overs)) | {
        "material": material, "spec": spec, "status": "failed", "over": overs[0], "input": path,
        "input_sha256": fingerprint["input_sha256"], "brdfz_version": brdfz.__version__,
        "worker": _worker(), "started": _now(), "error": ""}
    # The record vouches for the output: it goes first and comes back last, so a task cut short
    # anywhere leaves no record for a rerun to trust.
    record.unlink(missing_ok=True)
    try:
        row["input_bytes"] = os.path.getsize(path)
        row["format"] = brdfz.format_of(path)
        cpu = time.process_time()
        t0 = time.perf_counter()
        ref = brdfz.load(path)
        t1 = time.perf_counter()
        trial = brdfz.trial(ref, spec, threads=threads)
        t2 = time.perf_counter()
        measured = {}
        for over in overs:
            measured[over] = trial.metrics if over == "grid" else brdfz.metrics(ref, trial.brdf, over=over,
                                                                                threads=threads)
        t3 = time.perf_counter()
        output.parent.mkdir(parents=True, exist_ok=True)
        # A write killed with its worker leaves the library's temporary beside the output.
        for stale in glob.glob(glob.escape(str(output)) + ".tmp-*"):
            os.unlink(stale)
        brdfz.save(trial.brdf, output, threads=threads, build_spec=trial.spec, source=path,
                   source_metrics=trial.metrics)
        t4 = time.perf_counter()
    except MemoryError:
        raise
    except Exception as e:  # noqa: BLE001 - every other failure is this task's result, not the batch's
        output.unlink(missing_ok=True)
        row["error"] = _one_line(e)
        return row
    for k, over in enumerate(overs):
        m = measured[over]
        for name in METRICS:
            row[name if k == 0 else f"{over}_{name}"] = getattr(m, name).mean
    row |= {"status": "ok", "bytes": trial.bytes, "eval_rate": trial.eval_rate,
            "build_seconds": trial.build_seconds, "output": str(output.relative_to(out_dir)),
            "build_spec": trial.spec, "describe": trial.describe, "notes": "; ".join(trial.notes),
            "ratio": row["input_bytes"] / trial.bytes, "file_bytes": output.stat().st_size,
            "load_seconds": t1 - t0, "measure_seconds": (t2 - t1 - trial.build_seconds) + (t3 - t2),
            "write_seconds": t4 - t3, "cpu_seconds": time.process_time() - cpu}
    _write_json(record, {"fingerprint": fingerprint, "row": row, "output_sha256": file_sha256(output)})
    return row


def reusable(out_dir: PathLike, material: str, spec: str, fingerprint: Dict[str, Any]) -> Optional[Row]:
    """The recorded row of a finished task whose fingerprint (input hash, spec, brdfz version, over)
    matches and whose output is still the file it wrote (its SHA-256); None when it must run."""
    output, record = _paths(out_dir, material, spec)
    try:
        doc = json.loads(record.read_text())
        row = doc["row"]
        if doc["fingerprint"] != fingerprint or row["status"] != "ok":
            return None
        return row if file_sha256(output) == doc["output_sha256"] else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


# ---------------------------------------------------------------------------------------------- engine

@dataclass
class Job:
    fn: Callable[..., Any]  # a module-level function, so that workers can import it
    args: tuple
    label: str              # shown by the progress bar
    memory: int = 0         # peak bytes, declared as the task's MEMORY resource
    name: str = ""          # part of the Dask key, after the function's name


def dask_setup(worker) -> None:
    """Run by the workers of the LocalCluster an Engine starts (its preload): Ctrl-C at a terminal
    reaches every process of the group, and the batch, not each worker, answers it by closing them."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def measures_directions() -> bool:
    """Whether this build's brdfz.metrics measures errors over direction pairs (over="directions")."""
    return "over" in inspect.signature(brdfz.metrics).parameters


def dask_available() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


class Engine:
    """Runs jobs here, one after the other (workers=1, no Dask needed), on a Dask LocalCluster of
    `workers` processes started when the first jobs arrive, or on the cluster behind `scheduler` (an
    address, or a distributed.Client). Use it as a context manager; map() yields each job with its
    result, or with the one-line error it ended with."""

    def __init__(self, workers: Optional[int] = None, scheduler: Any = None, *, threads_per_worker: int = 1,
                 memory_per_worker: Optional[int] = None, retries: int = 2, threads: Optional[int] = None):
        if workers is not None and scheduler is not None:
            raise ValueError("give workers or scheduler, not both")
        if workers is not None and workers < 1:
            raise ValueError(f"workers must be at least 1, not {workers}")
        if threads is not None and threads > brdfz.MAX_THREADS:
            raise ValueError(f"threads = {threads} is above the limit of {brdfz.MAX_THREADS} (0: one per hardware thread)")
        if workers is None and scheduler is None:
            workers = (os.cpu_count() or 1) if dask_available() else 1
        self.workers, self.scheduler = workers, scheduler
        self.threads_per_worker, self.memory_per_worker, self.retries = threads_per_worker, memory_per_worker, retries
        self._threads = threads
        self.client = self.cluster = None
        self.memory_slot = 0  # the largest MEMORY a worker declares; 0: none do

    @property
    def serial(self) -> bool:
        return self.scheduler is None and self.workers == 1

    def task_threads(self) -> int:
        """Library threads per task: all cores when serial, the cores per worker thread on a LocalCluster,
        one on a cluster of unknown machines (unless `threads` was given)."""
        if self._threads is not None:
            return self._threads
        if self.serial:
            return 0
        if self.scheduler is None:
            return max(1, (os.cpu_count() or 1) // (self.workers * self.threads_per_worker))
        return 1

    def __enter__(self) -> "Engine":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:
        if self.serial or self.client is not None:
            return
        try:
            from distributed import Client, LocalCluster
            from distributed.system import MEMORY_LIMIT
        except ImportError:
            raise RuntimeError("Dask is not installed (pip install 'brdfz[batch]'); --workers 1 runs the tasks "
                               "without it") from None
        if isinstance(self.scheduler, Client):
            self.client = self.scheduler
        elif self.scheduler is not None:
            self.client = Client(self.scheduler)
        else:
            memory = int(self.memory_per_worker or MEMORY_LIMIT // self.workers)
            # dashboard_address ":0": any free port, so that batches side by side do not contend for one.
            self.cluster = LocalCluster(n_workers=self.workers, threads_per_worker=self.threads_per_worker,
                                        processes=True, memory_limit=memory, resources={"MEMORY": memory},
                                        dashboard_address=":0", preload=[__name__])
            self.client = Client(self.cluster)
        workers = self.client.scheduler_info()["workers"].values()
        self.memory_slot = max((w.get("resources", {}).get("MEMORY", 0) for w in workers), default=0)
        if not self.memory_slot:
            print("batch: the workers declare no MEMORY resource, so tasks are not placed by memory "
                  "(start them with --resources MEMORY=BYTES)", file=sys.stderr)

    def stop_local(self) -> None:
        """Ends the tasks still running on a LocalCluster this engine started, with its workers (the
        next map() starts another); those on a cluster behind `scheduler` run on, cancelled or not."""
        if self.cluster is not None:
            self.close()

    def close(self) -> None:
        # The client first, releasing its results, then the workers, then the scheduler: a worker
        # removed while it holds a result, or a scheduler closed under running workers, logs a warning.
        if self.client is not None and self.client is not self.scheduler:
            self.client.close()
        if self.cluster is not None:
            self.cluster.scale(0)
            deadline = time.monotonic() + 30
            while self.cluster.workers and time.monotonic() < deadline:
                time.sleep(0.05)
            self.cluster.close()
        self.client = self.cluster = None

    def map(self, jobs: Sequence[Job], label: str) -> Iterator[Tuple[Job, Any, str]]:
        """(job, result, "") or (job, None, error) for each job as it finishes, with a progress bar on
        stderr. Leaving the loop early (an exception, Ctrl-C) cancels the jobs not finished."""
        if not jobs:
            return
        bar = report.Bar(label, len(jobs))
        if self.serial:
            for job in jobs:
                try:
                    result, error = job.fn(*job.args), ""
                except Exception as e:  # noqa: BLE001 - the job's failure, reported with it
                    result, error = None, _one_line(e)
                bar.step(job.label)
                yield job, result, error
            return
        self.start()
        from distributed import as_completed

        futures = {}
        for job in jobs:
            extra = {}
            if self.memory_slot:
                extra["resources"] = {"MEMORY": min(job.memory, self.memory_slot)}
            key = "-".join(filter(None, [job.fn.__name__, job.name, uuid.uuid4().hex]))
            futures[self.client.submit(job.fn, *job.args, key=key, retries=self.retries, **extra)] = job
        if any(job.memory > self.memory_slot for job in jobs) and self.memory_slot:
            print(f"batch: some tasks may need more than the {self.memory_slot / 1e9:.2g} GB a worker declares; "
                  "they run one at a time on a worker", file=sys.stderr)
        try:
            for future in as_completed(list(futures)):
                job = futures.pop(future)
                try:
                    result, error = future.result(), ""
                except Exception as e:  # noqa: BLE001 - retries exhausted, workers lost: the job's end
                    result, error = None, _one_line(e)
                future.release()
                bar.step(job.label)
                yield job, result, error
        finally:
            if futures:
                self.client.cancel(list(futures))


# ----------------------------------------------------------------------------------------- catalogue

_INTEGER = {"bytes", "input_bytes", "file_bytes"}
_TEXT = {"material", "spec", "status", "output", "error", "over", "build_spec", "describe", "notes", "format",
         "input", "input_sha256", "worker", "started", "brdfz_version"}


class Catalogue:
    """DIR/catalogue.csv (and .parquet with pyarrow): the finished rows in input order, rewritten
    atomically at most every `interval` seconds and when forced."""

    def __init__(self, out: pathlib.Path, cols: Sequence[str], order: Sequence[Tuple[str, str]],
                 interval: float = 2.0):
        self.out, self.cols, self.order, self.interval = out, list(cols), list(order), interval
        self.by_key: Dict[Tuple[str, str], Row] = {}
        self.written = -1.0

    def add(self, row: Row) -> None:
        self.by_key[(row["material"], row["spec"])] = row

    def rows(self) -> List[Row]:
        return [self.by_key[k] for k in self.order if k in self.by_key]

    def write(self, force: bool = False) -> None:
        if not force and time.monotonic() - self.written < self.interval:
            return
        rows = self.rows()
        report.write_csv(rows, self.out / "catalogue.csv", self.cols)
        self._write_parquet(rows)
        self.written = time.monotonic()

    def _write_parquet(self, rows: Sequence[Row]) -> None:
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            return
        types = {c: pa.string() if c in _TEXT else pa.int64() if c in _INTEGER else pa.float64() for c in self.cols}
        schema = pa.schema([(c, types[c]) for c in self.cols])
        table = pa.Table.from_pylist([{c: r.get(c) for c in self.cols} for r in rows], schema=schema)
        path = self.out / "catalogue.parquet"
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            pq.write_table(table, tmp)
            os.replace(tmp, path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise


def failed_row(material: str, path: pathlib.Path, spec: str, overs: Sequence[str], error: str,
               fingerprint: Dict[str, Any]) -> Row:
    """The row of a task that ended without returning one (its workers died, it kept raising)."""
    return dict.fromkeys(columns(overs)) | {
        "material": material, "spec": spec, "status": "failed", "error": error, "over": overs[0],
        "input": str(path), "input_sha256": fingerprint["input_sha256"], "brdfz_version": brdfz.__version__}


# ---------------------------------------------------------------------------------------------- run

def _overs(over: Union[str, Sequence[str]]) -> Tuple[str, ...]:
    overs = (over,) if isinstance(over, str) else tuple(over)
    bad = [o for o in overs if o not in OVERS]
    if not overs or bad or len(set(overs)) != len(overs):
        raise ValueError(f"over must be 'grid' or 'directions' (or both, once each), not {over!r}")
    return overs


def _unique_specs(specs: Sequence[str]) -> List[str]:
    """Equivalent spellings of a setting as one task, under the first spelling given."""
    unique: Dict[str, str] = {}
    for s in specs:
        unique.setdefault(normalise_spec(s), s.strip())
    if not unique or any(not s for s in unique.values()):
        raise ValueError("give at least one spec, none empty")
    return list(unique.values())


def run(materials: Sequence[PathLike], specs: Union[Sequence[str], Callable[[pathlib.Path], Sequence[str]]],
        out: PathLike, *, workers: Optional[int] = None, scheduler: Any = None,
        over: Union[str, Sequence[str]] = "directions",
        budgets: Sequence[float] = DEFAULT_BUDGETS, force: bool = False, retries: int = 2,
        threads: Optional[int] = None, memory_per_worker: Optional[int] = None, charts: bool = True,
        render_size: int = 0, engine: Optional[Engine] = None) -> List[Row]:
    """Every spec on every material (files, or folders of them) into `out`, as the command does; returns
    the catalogue's rows (dicts with columns(over); numbers as numbers, missing values None). `specs`
    may instead be a function of a material's file giving that material's own. `over` names the errors'
    domain, "directions" (the default) or "grid"; a pair measures both, the second in columns
    <over>_<metric>. `engine` runs the tasks on a cluster the caller holds (it then ignores `workers`,
    `scheduler`, `retries`, `threads` and `memory_per_worker`). Charts (matplotlib) and summary.md
    unless charts=False; render_size > 0 adds sphere renders of each material's Pareto-optimal
    settings."""
    overs = _overs(over)
    named = material_names(material_files(materials))
    if not named:
        raise ValueError("no materials: give BRDF files or folders holding them")
    specs_of = {name: _unique_specs(specs(path) if callable(specs) else specs) for name, path in named.items()}
    out = pathlib.Path(out)
    cols = columns(overs)
    catalogue = Catalogue(out, cols, [(m, s) for m in named for s in specs_of[m]])
    fingerprints = {}
    jobs = []
    own = engine is None
    engine = engine or Engine(workers, scheduler, retries=retries, threads=threads, memory_per_worker=memory_per_worker)
    for name, path in named.items():
        digest = file_sha256(path)
        for spec in specs_of[name]:
            fp = {"input_sha256": digest, "spec": normalise_spec(spec), "brdfz_version": brdfz.__version__,
                  "over": list(overs)}
            fingerprints[(name, spec)] = fp
            row = None if force else reusable(out, name, spec, fp)
            if row is not None:
                catalogue.add(row | {"spec": spec})
            else:
                jobs.append(Job(build_task, (name, str(path), spec, str(out), overs, engine.task_threads(), fp),
                                f"{name} {spec}", estimate_memory(path.stat().st_size, spec), f"{name}/{spec_hash(spec)}"))
    reused = len(catalogue.by_key)
    started = time.monotonic()
    try:
        if jobs:
            # Before anything is written: a cluster that cannot be reached, or no Dask, leaves nothing.
            engine.start()
        out.mkdir(parents=True, exist_ok=True)
        print(f"batch: {len(jobs)} tasks to run, {reused} finished before", file=sys.stderr)
        try:
            for job, row, error in engine.map(jobs, "batch"):
                if error:
                    name, path, spec = job.args[0], job.args[1], job.args[2]
                    row = failed_row(name, pathlib.Path(path), spec, overs, error, fingerprints[(name, spec)])
                catalogue.add(row)
                catalogue.write()
        except BaseException:
            # Cut short (Ctrl-C): this machine's workers are stopped first, so that no task writes an
            # output and its record after the catalogue below has looked for them.
            engine.stop_local()
            raise
        finally:
            # Cut short: tasks that finished on a worker before their result arrived have their record.
            for name, _, spec in (job.args[:3] for job in jobs):
                if (name, spec) not in catalogue.by_key:
                    row = reusable(out, name, spec, fingerprints[(name, spec)])
                    if row is not None:
                        catalogue.add(row | {"spec": spec})
            catalogue.write(force=True)
        rows = catalogue.rows()
        renders = render_all(engine, out, rows, named, render_size) if render_size > 0 else []
    finally:
        if own:
            engine.close()
    failed = sum(not report.ok(r) for r in rows)
    print(f"batch: {len(rows)} rows ({failed} failed, {reused} reused) in {time.monotonic() - started:.0f} s; "
          f"{out / 'catalogue.csv'}", file=sys.stderr)
    if charts:
        auto = report.budget_choice(rows, budgets)
        names = write_charts(out, rows, auto)
        if names is not None:
            report.write_summary(out, "brdfz batch", rows, names, source="brdfz.batch", table="catalogue.csv",
                                 renders=renders, auto=auto,
                                 auto_heading="Smallest setting within each cos_rmse_rel budget")
    return rows


def write_charts(out: pathlib.Path, rows: Sequence[Row], auto: Sequence[Row]) -> Optional[List[str]]:
    """report.write_charts, or None (with a note) when matplotlib is missing or nothing succeeded."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print("batch: matplotlib is not installed, so no charts or summary.md (pip install 'brdfz[batch]')",
              file=sys.stderr)
        return None
    return report.write_charts(out, rows, auto)


# ------------------------------------------------------------------------------------------- renders

def render_task(name: str, path: str, reps: Sequence[Row], outputs: Sequence[Optional[str]], png: str, size: int,
                env_samples: int) -> str:
    """One material's renders (report.render_material): each representative read from its output
    file, or built again when it has none (a sweep CSV's rows). Written atomically."""
    ref = brdfz.load(path)
    brdfs = [brdfz.load(o) if o else brdfz.compress(ref, r["spec"]) for r, o in zip(reps, outputs)]
    target = pathlib.Path(png)
    tmp = target.with_name(f".{target.stem}.{os.getpid()}.tmp.png")
    report.render_material(name, ref, reps, brdfs, tmp, size, env_samples)
    os.replace(tmp, target)
    return png


def render_all(engine: Engine, out: pathlib.Path, rows: Sequence[Row], named: Dict[str, pathlib.Path], size: int,
               env_samples: Optional[int] = None) -> List[str]:
    """Sphere renders of each material's representatives into out/renders/, one task per material;
    returns the image paths relative to `out` that were written."""
    (out / "renders").mkdir(exist_ok=True)
    env_samples = env_samples or (32 if size <= 64 else 128)
    jobs = []
    error = report.error_column(rows)
    for name, mine in report.by_material(rows).items():
        reps = report.representatives(mine, error=error)
        if reps and name in named:
            outputs = [str(out / r["output"]) if r.get("output") else None for r in reps]
            jobs.append(Job(render_task, (name, str(named[name]), reps, outputs, str(out / "renders" / f"{name}.png"),
                                          size, env_samples), name, estimate_memory(named[name].stat().st_size, "")))
    done = []
    for job, _, error in engine.map(jobs, "renders"):
        if error:
            print(f"renders: {job.label}: {error}", file=sys.stderr)
        else:
            done.append(f"renders/{job.label}.png")
    return sorted(done)


VIEWS = ("polar", "slices", "compare")


def views_task(name: str, path: str, pick: Optional[Row], output: Optional[str], folder: str) -> List[str]:
    """One material's views (brdfz.plot) into folder/<name>_{polar,slices,compare}.png: its incidence-plane
    polar plot and θh×θd image beside those of `pick` (a sweep row: the smallest setting within 2 %, else
    5 %), and pick's relative error in both; without a pick, the material alone. Written atomically."""
    import matplotlib.pyplot as plt

    from brdfz import plot

    ref = brdfz.load(path)
    items = {name: ref}
    if pick:
        items[f"{pick['spec']} ({int(report.value(pick, 'bytes')):,} B)"] = brdfz.load(output) if output else \
            brdfz.compress(ref, pick["spec"])
    figures = {"polar": lambda: plot.polar(items, theta_i=(0, 30, 60)),
               "slices": lambda: plot.theta_h_theta_d(items)}
    if pick:
        figures["compare"] = lambda: _side_by_side(plot.polar(items, theta_i=(30, 60), error="relative"),
                                                   plot.theta_h_theta_d(items, error="relative"))
    written = []
    for kind, draw in figures.items():
        target = pathlib.Path(folder) / f"{name}_{kind}.png"
        tmp = target.with_name(f".{target.stem}.{os.getpid()}.tmp.png")
        fig = draw()
        fig.savefig(tmp, dpi=80)
        plt.close(fig)
        os.replace(tmp, target)
        written.append(str(target))
    return written


def _side_by_side(*figures):
    """The figures' images in one figure, left to right (each drawn by brdfz.plot at its own size)."""
    import matplotlib.pyplot as plt
    import numpy as np

    images = []
    for fig in figures:
        fig.canvas.draw()
        images.append(np.asarray(fig.canvas.buffer_rgba()))
        plt.close(fig)
    height = max(i.shape[0] for i in images)
    width = sum(i.shape[1] for i in images)
    out = plt.figure(figsize=(width / 100, height / 100), dpi=100)
    x = 0
    for image in images:
        ax = out.add_axes([x / width, 1 - image.shape[0] / height, image.shape[1] / width, image.shape[0] / height])
        ax.imshow(image)
        ax.axis("off")
        x += image.shape[1]
    return out


def views_all(engine: Engine, out: pathlib.Path, rows: Sequence[Row], named: Dict[str, pathlib.Path]) -> List[str]:
    """Each material's views (views_task) into out/views/, one task per material; returns the image paths
    relative to `out` that were written."""
    (out / "views").mkdir(exist_ok=True)
    jobs = []
    error = report.error_column(rows)
    for name, mine in report.by_material(rows).items():
        if name not in named:
            continue
        pick = report.smallest_within(mine, 0.02, error) or report.smallest_within(mine, 0.05, error)
        output = str(out / pick["output"]) if pick and pick.get("output") else None
        jobs.append(Job(views_task, (name, str(named[name]), pick, output, str(out / "views")), name,
                        estimate_memory(named[name].stat().st_size, "")))
    done = []
    for job, result, error in engine.map(jobs, "views"):
        if error:
            print(f"views: {job.label}: {error}", file=sys.stderr)
        else:
            done += [str(pathlib.Path(p).relative_to(out)) for p in result]
    return sorted(done)


# ---------------------------------------------------------------------------------------------- main

def engine_arguments(p: argparse.ArgumentParser) -> None:
    """The cluster options of every command that runs on brdfz.batch."""
    g = p.add_argument_group("cluster")
    where = g.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="a Dask LocalCluster of N worker processes (default: one per CPU; 1: no Dask)")
    where.add_argument("--scheduler", metavar="ADDR", help="the scheduler of an existing Dask cluster")
    g.add_argument("--retries", type=int, default=2, metavar="N", help="retries of a task that raises (default 2)")
    g.add_argument("--threads", type=int, metavar="T", help="library threads per task (default: the cores per "
                                                            "worker; 1 on --scheduler; all with --workers 1)")
    g.add_argument("--memory-per-worker", type=float, metavar="BYTES",
                   help="each local worker's memory limit and MEMORY resource (default: the machine's / N)")
    g.add_argument("--force", action="store_true", help="rebuild every task, even those finished before")


def engine_of(args: argparse.Namespace) -> Engine:
    return Engine(args.workers, args.scheduler, retries=args.retries, threads=args.threads,
                  memory_per_worker=None if args.memory_per_worker is None else int(args.memory_per_worker))


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m brdfz.batch", description=__doc__.split("\n\n")[0])
    p.add_argument("materials", nargs="+", metavar="MATERIAL_OR_DIR", help="BRDF files or folders of them")
    p.add_argument("--specs", nargs="+", required=True, metavar="SPEC", help="representation specs (docs/repr-specs.md)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--over", choices=OVERS, default="directions",
                   help="errors over direction pairs uniform in solid angle (default) or over the grid")
    p.add_argument("--budgets", nargs="*", type=float, default=DEFAULT_BUDGETS, metavar="E",
                   help=f"cos_rmse_rel budgets of the choice in the charts and summary (default {DEFAULT_BUDGETS})")
    p.add_argument("--render-size", type=int, default=0, metavar="N", help="sphere renders of N pixels (default 0: none)")
    p.add_argument("--no-charts", action="store_true", help="only the outputs and the catalogue")
    engine_arguments(p)
    args = p.parse_args(argv)
    try:
        with engine_of(args) as engine:
            rows = run(args.materials, args.specs, args.out, over=args.over, budgets=args.budgets, force=args.force,
                       charts=not args.no_charts, render_size=args.render_size, engine=engine)
    except KeyboardInterrupt:
        print(f"batch: interrupted; {pathlib.Path(args.out) / 'catalogue.csv'} holds the tasks that finished",
              file=sys.stderr)
        return 130
    except (ValueError, OSError, RuntimeError) as e:
        print(f"batch: {e}", file=sys.stderr)
        return 1
    failed = sum(not report.ok(r) for r in rows)
    print(f"{len(rows) - failed} of {len(rows)} tasks ok; catalogue {pathlib.Path(args.out) / 'catalogue.csv'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
