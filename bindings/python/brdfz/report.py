"""What a person reads of a catalogue (brdfz.batch) or a benchmark sweep (brdfz.bench): Pareto fronts,
size / speed against error charts, sphere renders, the choice at error budgets and summary.md.

Rows are catalogue rows (brdfz.batch.COLUMNS): dicts with at least material, spec, status ("ok" or
"failed"), bytes, the error metrics, eval_rate and build_seconds; values may be numbers or the text of
a CSV. Charts need matplotlib (imported when drawing).
"""
from __future__ import annotations

import csv
import datetime
import errno
import math
import os
import pathlib
import platform
import secrets
import stat
import sys
from typing import Any, Dict, Iterable, List, Optional, Sequence

import numpy as np

import brdfz

Row = Dict[str, Any]

METRICS = ["cos_rmse_rel", "cos_rmse", "log_rmse", "cbrt_rmse"]
# Columns of the error measured over direction pairs (brdfz.metrics(over="directions")), when measured,
# in the order of the grid's columns.
DIRECTIONS_METRICS = ["directions_" + m for m in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse")]
DEFAULT_BUDGETS = [0.02, 0.05]
# Log axes cannot show 0: smaller errors (a lossless table) are drawn at this floor.
ERROR_FLOOR = 1e-6
AUTO_COLUMNS = ["material", "budget", "chosen", "bytes", "cos_rmse_rel", "eval_pairs_per_s", "build_s", "tried"]
# Catalogue column -> the column of the same quantity in auto rows.
_AUTO_NAME = {"bytes": "bytes", "eval_rate": "eval_pairs_per_s"}
_AXIS_LABEL = {"bytes": "bytes", "eval_rate": "eval pairs/s (one thread)"}


# ----------------------------------------------------------------------------------------------- rows

def value(row: Row, key: str) -> float:
    """A numeric cell as a float; NaN when empty or absent."""
    v = row.get(key)
    return math.nan if v is None or v == "" else float(v)


def ok(row: Row) -> bool:
    return row["status"] == "ok"


def by_material(rows: Iterable[Row]) -> Dict[str, List[Row]]:
    out: Dict[str, List[Row]] = {}
    for r in rows:
        out.setdefault(r["material"], []).append(r)
    return out


def has_directions(rows: Sequence[Row]) -> bool:
    return any(ok(r) and r.get("directions_cos_rmse_rel") not in (None, "") for r in rows)


def error_column(rows: Sequence[Row]) -> str:
    """The cos_rmse_rel column that fronts, budget choices, charts and summaries judge by: over direction
    pairs wherever measured (what a renderer sees; the grid's bins weigh pairs otherwise), else the rows'
    own (over the grid for a sweep CSV without directions_*, a catalogue's `over` for a batch's)."""
    return "directions_cos_rmse_rel" if has_directions(rows) else "cos_rmse_rel"


def frame(rows: Sequence[Row]) -> str:
    """Where error_column(rows) was measured: "directions" or "grid"."""
    return "directions" if has_directions(rows) or any(ok(r) and r.get("over") == "directions" for r in rows) \
        else "grid"


def method(spec: str) -> str:
    """The method a setting belongs to, for colours and per-method fronts: its kind, and the stored
    type of tables ("tabular u8log")."""
    kind, _, options = spec.partition(":")
    dtype = [o.split("=", 1)[1] for o in options.split(",") if o.startswith("dtype=")]
    return kind + (" " + dtype[0] if dtype else "")


def pareto_front(xs: Sequence[float], ys: Sequence[float], *, maximize_x: bool = False) -> List[int]:
    """Indices of the points no other point beats in both coordinates (smaller y, and smaller x, or
    larger with maximize_x), ordered along x from best to worst. Of equal points, the first is kept."""
    sign = -1.0 if maximize_x else 1.0
    order = sorted(range(len(xs)), key=lambda i: (sign * xs[i], ys[i], i))
    front, best_y = [], math.inf
    for i in order:
        if ys[i] < best_y:
            front.append(i)
            best_y = ys[i]
    return front


def size_front(rows: Sequence[Row], error: Optional[str] = None) -> List[Row]:
    """The ok rows on the bytes vs cos_rmse_rel Pareto front (the `error` column, default
    error_column(rows)), smallest first."""
    error = error or error_column(rows)
    good = [r for r in rows if ok(r)]
    return [good[i] for i in pareto_front([value(r, "bytes") for r in good], [value(r, error) for r in good])]


def representatives(rows: Sequence[Row], count: int = 4, error: Optional[str] = None) -> List[Row]:
    """Up to `count` settings spread along the material's size vs cos_rmse_rel Pareto front."""
    front = size_front(rows, error)
    if len(front) <= count:
        return front
    return [front[round(k * (len(front) - 1) / (count - 1))] for k in range(count)]


def smallest_within(rows: Sequence[Row], limit: float, error: Optional[str] = None) -> Optional[Row]:
    error = error or error_column(rows)
    fits = [r for r in rows if ok(r) and value(r, error) <= limit]
    return min(fits, key=lambda r: value(r, "bytes")) if fits else None


def budget_choice(rows: Sequence[Row], budgets: Sequence[float]) -> List[Row]:
    """Per material and budget, the smallest setting of the catalogue whose cos_rmse_rel (error_column)
    is within the budget: the choice `brdfz compress --auto --metric cos` makes with these settings as
    candidates. Rows with AUTO_COLUMNS, their cos_rmse_rel that column's; "chosen" empty when none is."""
    error = error_column(rows)
    out = []
    for name, mine in by_material(rows).items():
        for budget in budgets:
            r = smallest_within(mine, budget, error)
            a = dict.fromkeys(AUTO_COLUMNS, "") | {"material": name, "budget": f"{budget:g}",
                                                   "tried": str(sum(ok(x) for x in mine))}
            if r:
                a |= {"chosen": r["spec"], "bytes": str(int(value(r, "bytes"))), "cos_rmse_rel": fmt(r[error]),
                      "eval_pairs_per_s": fmt(r["eval_rate"]), "build_s": fmt(r["build_seconds"])}
            out.append(a)
    return out


# ---------------------------------------------------------------------------------------------- files

def fmt(v: Any) -> str:
    """A cell as CSV text: numbers as C's %.6g (bench/compress_sweep's), None as empty."""
    if v is None:
        return ""
    if isinstance(v, float):
        return format(v, ".6g")
    return str(v)


def atomic_write(path: pathlib.Path, write) -> None:
    """write(file object) into a temporary file beside `path`, then rename it over `path`: readers see
    the old file or the new one, never part of one. As the library's writers (formats/detail/atomic_file.h):
    a new file gets 0666 less the umask, a replaced one keeps its mode, a symbolic link to a regular
    file is written through, and anything else that is not a regular file is refused. Errors name
    `path`, not the temporary."""
    path = pathlib.Path(path)
    try:
        target = _write_target(path)
        while True:
            tmp = target.with_name(f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
            try:
                # Created by open(2), so the umask applies (mkstemp's files are 0600 whatever it is).
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
                break
            except FileExistsError:
                continue
        try:
            with os.fdopen(fd, "w", newline="") as f:
                write(f)
                if target.exists():
                    os.chmod(f.fileno(), stat.S_IMODE(target.stat().st_mode))
            os.replace(tmp, target)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    except OSError as e:
        raise OSError(e.errno, e.strerror, str(path)) from None


def _write_target(path: pathlib.Path) -> pathlib.Path:
    """Where atomic_write puts the bytes of `path`: itself, or the regular file a link leads to."""
    target = pathlib.Path(os.path.realpath(path)) if path.is_symlink() else path
    try:
        mode = target.lstat().st_mode
    except FileNotFoundError:
        if target is path:
            return path
        raise OSError(errno.ENOENT, "is a symbolic link to a missing file; only regular files are written") from None
    if not stat.S_ISREG(mode):
        raise OSError(errno.EINVAL, "is not a regular file; only regular files are written")
    return target


def write_csv(rows: Sequence[Row], path: pathlib.Path, columns: Sequence[str]) -> None:
    def write(f):
        w = csv.DictWriter(f, fieldnames=columns, lineterminator="\n", extrasaction="ignore")
        w.writeheader()
        w.writerows({c: fmt(r.get(c)) for c in columns} for r in rows)

    atomic_write(path, write)


class Bar:
    """A progress bar on stderr, "label  37% [#######.............] 12/32 what", rewritten in place on a
    terminal; elsewhere (logs) one line per finished step."""

    def __init__(self, label: str, total: int, stream=None):
        self.label, self.total, self.done = label, max(total, 1), 0
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()

    def _line(self, what: str) -> str:
        filled = 20 * self.done // self.total
        return (f"{self.label} {100 * self.done // self.total:3d}% [{'#' * filled}{'.' * (20 - filled)}]"
                f" {self.done}/{self.total} {what}")

    def step(self, what: str = "") -> None:
        self.done += 1
        if self.tty:
            self.stream.write("\r\033[K" + self._line(what) + ("\n" if self.done >= self.total else ""))
        else:
            self.stream.write(self._line(what) + "\n")
        self.stream.flush()


# --------------------------------------------------------------------------------------------- charts

def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _colours(methods: Sequence[str]) -> Dict[str, object]:
    names = sorted(set(methods))
    cmap = _plt().get_cmap("tab10" if len(names) <= 10 else "tab20")
    return {m: cmap(k % cmap.N) for k, m in enumerate(names)}


def _panels(n: int, title: str):
    plt = _plt()
    cols = min(4, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(max(4.2 * cols, 7.0), 3.6 * rows + 1.0), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize="medium")
    return fig, list(axes.flat[:n])


def _finish(fig, handles_from, path: pathlib.Path) -> None:
    handles = {}
    for ax in handles_from:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=min(6, len(handles)),
               fontsize="small", frameon=False)
    fig.tight_layout(rect=(0, 0.04 + 0.02 * math.ceil(len(handles) / 6), 1, 1))
    fig.savefig(path, dpi=90)
    _plt().close(fig)


def _short(spec: str) -> str:
    return spec.replace("tabular:", "").replace("analytic:", "")


def _label(ax, text: str, x: float, y: float) -> None:
    """A point's label placed towards the panel's inside (left of points in its right half, below
    points in its upper half), so that it stays within the panel rather than spilling into the next."""
    fx, fy = ax.transAxes.inverted().transform(ax.transData.transform((x, y)))
    right, top = fx > 0.5, fy > 0.5
    ax.annotate(text, (x, y), fontsize=6, xytext=(-4 if right else 4, -4 if top else 4), textcoords="offset points",
                ha="right" if right else "left", va="top" if top else "bottom", annotation_clip=True)


def _readable_log_ticks(ax) -> None:
    """Tick labels of a log-log panel that do not overlap: at most a few decades labelled when the data
    span several, 1-2-5 steps over less; minor ticks unlabelled (matplotlib labels them, crowded,
    when fewer than two decades show)."""
    from matplotlib.ticker import LogFormatterSciNotation, LogLocator, NullFormatter

    ax.autoscale_view()
    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        decades = math.log10(hi / lo) if lo > 0 and hi > lo else 1.0
        subs = (1.0,) if decades >= 1.5 else (1.0, 2.0, 5.0) if decades >= 0.6 else (1.0, 1.5, 2.0, 3.0, 5.0, 7.0)
        axis.set_major_locator(LogLocator(base=10, subs=subs, numticks=5 if axis is ax.xaxis else 7))
        axis.set_major_formatter(LogFormatterSciNotation(labelOnlyBase=False))
        axis.set_minor_formatter(NullFormatter())


def chart_tradeoff(rows: Sequence[Row], x: str, y: str, path: pathlib.Path, *, maximize_x: bool = False) -> None:
    """One log-log panel per material: every ok setting coloured by method, the Pareto front joined
    and its points labelled."""
    mats = by_material([r for r in rows if ok(r) and not math.isnan(value(r, y))])
    colours = _colours([method(r["spec"]) for r in rows])
    xlabel = _AXIS_LABEL[x]
    fig, axes = _panels(len(mats), f"{xlabel} vs {y}; Pareto front: black (errors < {ERROR_FLOOR:g} drawn at it)")
    for ax, (name, mine) in zip(axes, mats.items()):
        xs = [value(r, x) for r in mine]
        ys = [max(value(r, y), ERROR_FLOOR) for r in mine]
        for r, px, py in zip(mine, xs, ys):
            ax.scatter(px, py, color=colours[method(r["spec"])], label=method(r["spec"]), s=28, zorder=2)
        front = pareto_front(xs, ys, maximize_x=maximize_x)
        ax.plot([xs[i] for i in front], [ys[i] for i in front], "k-", lw=1, zorder=1, drawstyle="steps-post")
        ax.scatter([xs[i] for i in front], [ys[i] for i in front], facecolors="none", edgecolors="k", s=70, zorder=3)
        ax.set(xscale="log", yscale="log", title=name, xlabel=xlabel, ylabel=y)
        _readable_log_ticks(ax)
        for i in front:
            _label(ax, _short(mine[i]["spec"]), xs[i], ys[i])
        ax.grid(True, which="major", alpha=0.3)
    _finish(fig, axes, path)


def chart_auto(rows: Sequence[Row], auto: Sequence[Row], x: str, path: pathlib.Path) -> None:
    """Per material: each method's Pareto front (size or speed vs cos_rmse_rel, error_column(rows)) as a
    line, the setting chosen at each budget as a star."""
    error = error_column(rows)
    mats = by_material([r for r in rows if ok(r)])
    colours = _colours([method(r["spec"]) for r in rows])
    maximize_x = x == "eval_rate"
    fig, axes = _panels(len(mats), "chosen at each cos_rmse_rel budget (dotted) over each method's Pareto front")
    markers = "*PXD^v"
    budgets = sorted({a["budget"] for a in auto}, key=float)
    for ax, (name, mine) in zip(axes, mats.items()):
        for m in sorted({method(r["spec"]) for r in mine}):
            pts = [r for r in mine if method(r["spec"]) == m]
            xs = [value(r, x) for r in pts]
            ys = [max(value(r, error), ERROR_FLOOR) for r in pts]
            front = pareto_front(xs, ys, maximize_x=maximize_x)
            ax.plot([xs[i] for i in front], [ys[i] for i in front], "-o", color=colours[m], ms=3, lw=1, alpha=0.6,
                    label=m)
        chosen = [a for a in auto if a["material"] == name and a["chosen"]]
        for a in chosen:
            k = budgets.index(a["budget"]) % len(markers)
            ax.scatter(float(a[_AUTO_NAME[x]]), max(float(a["cos_rmse_rel"]), ERROR_FLOOR), marker=markers[k], s=160,
                       color="k", zorder=3, label=f"chosen at budget {a['budget']}")
        for b in budgets:
            ax.axhline(float(b), color="grey", ls=":", lw=1)
        ax.set(xscale="log", yscale="log", title=name, xlabel=_AXIS_LABEL[x], ylabel=f"cos_rmse_rel over {frame(rows)}")
        _readable_log_ticks(ax)
        for a in chosen:
            _label(ax, _short(a["chosen"]), float(a[_AUTO_NAME[x]]), max(float(a["cos_rmse_rel"]), ERROR_FLOOR))
        ax.grid(True, which="major", alpha=0.3)
    _finish(fig, axes, path)


def write_charts(out: pathlib.Path, rows: Sequence[Row], auto: Sequence[Row]) -> List[str]:
    """Every chart of a catalogue into `out`: bytes vs each error metric (over directions too when
    measured), eval speed vs error (error_column) and with `auto` rows the choices over the Pareto
    fronts. Returns the file names (none when no row is ok)."""
    if not any(ok(r) for r in rows):
        return []
    charts = []
    metrics = METRICS + (["directions_" + m for m in METRICS] if has_directions(rows) else [])
    for metric in metrics:
        chart_tradeoff(rows, "bytes", metric, out / f"size_vs_{metric}.png")
        charts.append(f"size_vs_{metric}.png")
    chart_tradeoff(rows, "eval_rate", error_column(rows), out / "speed_vs_error.png", maximize_x=True)
    charts.append("speed_vs_error.png")
    if auto:
        for x, name in (("bytes", "auto_size_vs_error.png"), ("eval_rate", "auto_speed_vs_error.png")):
            chart_auto(rows, auto, x, out / name)
            charts.append(name)
    return charts


# -------------------------------------------------------------------------------------------- renders

# The fixed lighting of every render: a directional light towards upper left front, and a sky that
# brightens upwards (world frame: x right, y up, z towards the viewer).
LIGHT = np.array([-0.45, 0.55, 0.7]) / np.linalg.norm([-0.45, 0.55, 0.7])
LIGHT_IRRADIANCE = 2.0


def sky(d: np.ndarray) -> np.ndarray:
    up = d[:, 1:2]
    return np.where(up > 0, 0.25 + 0.35 * up, 0.12 + 0.05 * up) * np.array([0.85, 0.95, 1.1])


def _local(d: np.ndarray, t: np.ndarray, b: np.ndarray, n: np.ndarray) -> np.ndarray:
    return np.stack([(d * t).sum(1), (d * b).sum(1), (d * n).sum(1)], axis=1)


def render_sphere(brdf: brdfz.Brdf, size: int = 128, env_samples: int = 64, *, light=LIGHT,
                  irradiance: float = LIGHT_IRRADIANCE, environment=sky, seed: int = 1, draws=None) -> np.ndarray:
    """Radiance (size, size, 3) of an orthographic unit sphere seen along -z: at each pixel the normal
    gives the local frame (brdf.h: normal +z), wo is the view direction. The light (a direction in the
    world frame) contributes f·cosθi·E; the environment (world directions (N, 3) -> radiance (N, 3)) is
    integrated by importance sampling with the Brdf's own sampler, `env_samples` stratified draws per
    pixel (the mean of weight·L), which follows a glossy lobe wherever it points (a fixed set of sky
    directions leaves a dot on a glossy sphere for each). Deterministic for a seed. Black outside.
    `draws`, a function (k, pixels) -> u (len(pixels), 2) in [0, 1), gives the k-th draw's u at
    `pixels` (flat indices into the row-major image) in place of the seeded strata."""
    if not (isinstance(size, int) and 1 <= size <= 8192):
        raise ValueError(f"size must be an integer in [1, 8192], not {size!r}")
    if not (isinstance(env_samples, int) and 0 <= env_samples <= 1 << 16):
        raise ValueError(f"env_samples must be an integer in [0, 65536], not {env_samples!r}")
    light = np.asarray(light, dtype=float)
    if light.shape != (3,) or not np.isfinite(light).all() or not light.any():
        raise ValueError(f"light must be a finite non-zero direction (3,), not {light!r}")
    light = light / np.linalg.norm(light)
    u = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(u, -u)
    inside = x * x + y * y < 1
    n = np.stack([x[inside], y[inside], np.sqrt(1 - x[inside] ** 2 - y[inside] ** 2)], axis=1)
    # An orthonormal tangent frame without a singularity (Duff et al. 2017).
    s = np.where(n[:, 2] >= 0, 1.0, -1.0)
    a = -1 / (s + n[:, 2])
    bb = n[:, 0] * n[:, 1] * a
    t = np.stack([1 + s * n[:, 0] ** 2 * a, s * bb, -s * n[:, 0]], axis=1)
    b = np.stack([bb, s + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    wo = _local(np.broadcast_to([0.0, 0.0, 1.0], n.shape), t, b, n)
    wi = _local(np.broadcast_to(light, n.shape), t, b, n)
    radiance = brdf.eval_cos(wi, wo) * irradiance
    if env_samples:
        # Jittered strata of a √n × √n grid of u (the rest uniform), drawn anew at each pixel, so that
        # neighbouring pixels share no pattern.
        rng = np.random.default_rng(seed)
        side = math.isqrt(env_samples)
        env = np.zeros_like(radiance)
        pixels = np.flatnonzero(inside)
        for k in range(env_samples):
            if draws is not None:
                draw = np.asarray(draws(k, pixels), dtype=float)
            elif k < side * side:
                draw = (np.array([k % side, k // side]) + rng.random((len(n), 2))) / side
            else:
                draw = rng.random((len(n), 2))
            d, pdf, weight = brdf.sample(wo, np.minimum(draw, np.nextafter(1.0, 0.0)))  # [0, 1) after rounding
            world = d[:, :1] * t + d[:, 1:2] * b + d[:, 2:3] * n
            env += np.where(pdf[:, None] > 0, weight * environment(world), 0.0)
        radiance += env / env_samples
    image = np.zeros((size, size, 3))
    image[inside] = radiance
    return image


def tone_map(image: np.ndarray, exposure: float) -> np.ndarray:
    return np.clip(image * exposure, 0, 1) ** (1 / 2.2)


def exposure_of(image: np.ndarray) -> float:
    """The exposure that maps the 99th percentile of a render's luminance to 0.8."""
    lum = image.mean(axis=2)
    return 0.8 / max(np.percentile(lum[lum > 0], 99) if (lum > 0).any() else 1.0, 1e-12)


def error_scale(errors: Sequence[np.ndarray]) -> float:
    """One colour scale for error images of several representations: the largest of their 99th
    percentiles, so that the worst one spans the scale and the better ones read as darker (a fixed
    gain saturates every image of a poor representation alike)."""
    tops = [float(np.percentile(e[e > 0], 99)) for e in errors if (e > 0).any()]
    return max(tops) if tops else 1.0


def render_material(name: str, ref: brdfz.Brdf, reps: Sequence[Row], brdfs: Sequence[brdfz.Brdf],
                    path: pathlib.Path, size: int, env_samples: int) -> None:
    """Reference and each representative setting (`reps`, built as `brdfs`) side by side, tone-mapped
    with the reference's exposure, and under each its absolute error relative to the reference's
    99th-percentile luminance, all on one colour scale (error_scale) with a colour bar."""
    plt = _plt()
    reference = render_sphere(ref, size, env_samples)
    exposure = exposure_of(reference)
    images = [render_sphere(brdf, size, env_samples) for brdf in brdfs]
    # Relative to the luminance that exposure maps to 0.8: an error of 0.1 is a tenth of a bright pixel.
    errors = [np.abs(image - reference).mean(axis=2) * exposure / 0.8 for image in images]
    top = error_scale(errors)
    fig, axes = plt.subplots(2, len(reps) + 1, figsize=(2.4 * (len(reps) + 1) + 0.8, 5.3), squeeze=False)
    axes[0][0].imshow(tone_map(reference, exposure))
    axes[0][0].set_title(f"{name}\nreference", fontsize=8)
    axes[1][0].text(0.5, 0.5, "|error| / bright pixel\n(one scale)", ha="center", va="center", fontsize=8)
    shown = None
    for k, (r, image, error) in enumerate(zip(reps, images, errors), start=1):
        axes[0][k].imshow(tone_map(image, exposure))
        axes[0][k].set_title(f"{r['spec']}\n{int(value(r, 'bytes')):,} B, cos_rmse_rel {value(r, 'cos_rmse_rel'):.3g}",
                             fontsize=7)
        shown = axes[1][k].imshow(error, cmap="magma", vmin=0, vmax=top)
        axes[1][k].set_title(f"99th pct {np.percentile(error[error > 0], 99) if (error > 0).any() else 0:.3g}",
                             fontsize=7)
    for ax in axes.flat:
        ax.axis("off")
    fig.tight_layout()
    if shown is not None:
        fig.colorbar(shown, ax=list(axes[1][1:]), shrink=0.8)
    fig.savefig(path, dpi=90)
    plt.close(fig)


# -------------------------------------------------------------------------------------------- summary

def _table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def _g(v: Any) -> str:
    return "" if v in (None, "") else f"{float(v):.3g}"


def _smallest_cells(rows: Sequence[Row], auto: Sequence[Row], limit: float, error: str) -> List[str]:
    """The smallest setting within `limit` in the `error` column among the material's rows and its budget
    choices (`auto`, measured in the same frame), so that the summary never says "none" where its own
    choices found one."""
    r = smallest_within(rows, limit, error)
    best = (value(r, "bytes"), f"`{r['spec']}`") if r else None
    for a in auto:
        if a["chosen"] and value(a, "cos_rmse_rel") <= limit and (best is None or value(a, "bytes") < best[0]):
            best = (value(a, "bytes"), f"`{a['chosen']}` (budget choice)")
    return [best[1], f"{int(best[0]):,}"] if best else ["none", ""]


def write_summary(out: pathlib.Path, title: str, rows: Sequence[Row], charts: Sequence[str], *,
                  source: str, table: str, renders: Sequence[str] = (), views: Sequence[str] = (),
                  auto: Sequence[Row] = (), auto_heading: str = "") -> pathlib.Path:
    """out/summary.md: the smallest setting within 2 % and 5 %, every chart, each material's Pareto
    front, eval speed per method, the choices at the budgets (`auto`, under `auto_heading`: measured in
    the frame of error_column(rows)), the renders, the views (polar plots, θh×θd images, comparisons)
    and the failed tasks, all judged by error_column(rows). `table` names the file with every row."""
    mats = by_material(rows)
    chosen = by_material(auto)
    directions = has_directions(rows)
    error = error_column(rows)
    primary = "directions" if not directions and frame(rows) == "directions" else "grid"
    over = {"grid": "over the grid", "directions": "over direction pairs uniform in solid angle"}
    md = [f"# {title}\n",
          f"{len(mats)} materials × {len({r['spec'] for r in rows})} settings from {source}; "
          f"{datetime.date.today()}, {platform.node()} ({os.cpu_count()} CPUs, {platform.processor() or platform.machine()}). "
          "Errors are against each material's own data (cos_rmse_rel: cosine-weighted RMSE relative to the "
          f"reference's RMS, channel mean; {over[primary]}"
          + (f", and {over['directions']}: directions_*" if directions else "")
          + f"); settings are judged (fronts, smallest within an error, choices, renders) by cos_rmse_rel "
          f"{over[frame(rows)]}. Eval speed is batch eval on one thread. All rows: [{table}]({table}).\n",
          "## Smallest setting within an error\n",
          "Of the settings measured and of the budget choices (below).\n" if auto else "",
          _table(["material", "≤ 2 % cos_rmse_rel", "bytes", "≤ 5 % cos_rmse_rel", "bytes"],
                 [[m, *_smallest_cells(mine, chosen.get(m, []), 0.02, error),
                   *_smallest_cells(mine, chosen.get(m, []), 0.05, error)] for m, mine in mats.items()]),
          "## Size and speed against error\n"]
    md += [f"![{c}]({c})\n" for c in charts if not c.startswith("auto_")]
    md.append(f"## Pareto-optimal settings (bytes vs cos_rmse_rel {over[frame(rows)]})\n")
    header = ["setting", "bytes", "ratio", "cos_rmse_rel", "log_rmse", "eval pairs/s", "build s"]
    for m, mine in mats.items():
        cells = [[f"`{r['spec']}`", f"{int(value(r, 'bytes')):,}", _g(r.get("ratio")), _g(r["cos_rmse_rel"]),
                  _g(r["log_rmse"]), _g(r["eval_rate"]), _g(r["build_seconds"])]
                 + ([_g(r.get("directions_cos_rmse_rel"))] if directions else []) for r in size_front(mine, error)]
        md += [f"### {m}\n", _table(header + (["cos_rmse_rel over directions"] if directions else []), cells)]
    speeds: Dict[str, List[float]] = {}
    for r in rows:
        if ok(r):
            speeds.setdefault(method(r["spec"]), []).append(value(r, "eval_rate"))
    md += ["## Eval speed per method (pairs/s, one thread, over materials and settings)\n",
           _table(["method", "median", "min", "max"],
                  [[m, f"{np.median(v):.3g}", f"{min(v):.3g}", f"{max(v):.3g}"] for m, v in sorted(speeds.items())])]
    if auto:
        md += [f"## {auto_heading}\n",
               _table(["material", "budget", "chosen", "bytes", "cos_rmse_rel", "eval pairs/s", "candidates tried"],
                      [[a["material"], a["budget"], f"`{a['chosen']}`" if a["chosen"] else "none within the budget",
                        f"{int(a['bytes']):,}" if a["bytes"] else "", _g(a["cos_rmse_rel"]),
                        _g(a["eval_pairs_per_s"]), a["tried"]] for a in auto])]
        md += [f"![{c}]({c})\n" for c in charts if c.startswith("auto_")]
    if renders:
        md.append("## Renders (reference, Pareto-optimal settings, error on one scale)\n")
        md += [f"![{r}]({r})\n" for r in renders]
    if views:
        md.append("## Views (the material and its smallest setting within 2 % or 5 %: polar plots, θh×θd images, "
                  "relative error)\n")
        md += [f"![{v}]({v})\n" for v in views]
    failed = [r for r in rows if not ok(r)]
    if failed:
        md += ["## Failed\n",
               _table(["material", "setting", "error"], [[r["material"], f"`{r['spec']}`", r["error"]] for r in failed])]
    path = out / "summary.md"
    atomic_write(path, lambda f: f.write("\n".join(md)))
    return path
