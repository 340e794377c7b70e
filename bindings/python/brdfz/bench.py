"""The compression benchmark: every representation setting over a set of materials.

    python -m brdfz.bench [--materials DIR_OR_FILE ...] [--specs SPEC ...] [--out DIR] [--quick]
                          [--from-csv FILE] [--budgets E ...] [--candidates SPEC ...] [--render-size N]

Materials default to ../shared/data/rgl/*.bsdf and the MERL tables in $BRDFZ_MERL_DIR (else
build/merl-tables), relative to the current folder (the repository root). Settings default to
brdfz.benchmark_specs(). Each (material, setting) is measured by brdfz.trial(), the numbers
`brdfz compress` prints; a setting that fails (e.g. a kind this build lacks) is a row with status
"error: ...". Writes into --out (default bench-out/):

    sweep.csv                    the columns of bench/compress_sweep (COLUMNS)
    size_vs_<metric>.png         bytes vs each error metric, log-log, one panel per material, Pareto front marked
    speed_vs_error.png           eval speed vs cos_rmse_rel, Pareto front (fast and accurate) marked
    renders/<material>.png       a sphere under a fixed light and sky: reference, the Pareto-optimal
                                 settings and their ×10 error images
    auto.csv, auto_size_vs_error.png, auto_speed_vs_error.png
                                 brdfz.compress(auto=True, metric="cos") at each budget, the chosen
                                 representations drawn over each method's Pareto front
    summary.md                   tables and every image above

--from-csv FILE draws from an existing sweep CSV (this program's or bench/compress_sweep's) instead of
sweeping; renders and the auto selection then use the --materials files whose names match its rows.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import math
import os
import pathlib
import platform
import sys
import time
from typing import Dict, List, Optional, Sequence

import numpy as np

import brdfz

COLUMNS = ["material", "format", "repr", "describe", "bytes", "input_bytes", "ratio", "cos_rmse", "cos_rmse_rel",
           "log_rmse", "cbrt_rmse", "eval_pairs_per_s", "build_s", "status"]
METRICS = ["cos_rmse_rel", "cos_rmse", "log_rmse", "cbrt_rmse"]
# --quick: one setting of each kind, small enough for a smoke run.
QUICK_SPECS = ["tabular:res=45x45x90", "tabular:res=16x16x32,dtype=u8log", "bivariate:res=32x32,dtype=f16",
               "svd:rank=2,space=log", "nmf:rank=2", "analytic:lambert+ggx"]
DEFAULT_BUDGETS = [0.02, 0.05]
# Log axes cannot show 0: smaller errors (a lossless table) are drawn at this floor.
ERROR_FLOOR = 1e-6

Row = Dict[str, str]


# ---------------------------------------------------------------------------------------------- data

def default_materials() -> List[pathlib.Path]:
    rgl = sorted(pathlib.Path("../shared/data/rgl").glob("*.bsdf"))
    merl_dir = pathlib.Path(os.environ.get("BRDFZ_MERL_DIR") or "build/merl-tables")
    return rgl + sorted(merl_dir.glob("*.binary"))


def material_files(names: Sequence[str]) -> List[pathlib.Path]:
    """Files named, and the BRDF files inside folders named."""
    out = []
    for name in names:
        p = pathlib.Path(name)
        if p.is_dir():
            out += sorted(f for f in p.iterdir() if f.suffix in (".binary", ".bsdf", ".brdfz"))
        elif p.exists():
            out.append(p)
        else:
            raise FileNotFoundError(f"{name}: no such file or folder")
    return out


def _num(v: float) -> str:
    return format(v, ".6g")  # as the C++ sweep's %.6g


def trial_row(material: str, fmt: str, spec: str, input_bytes: int, t: Optional[brdfz.Trial] = None,
              error: str = "") -> Row:
    if t is None:
        return dict.fromkeys(COLUMNS, "") | {"material": material, "format": fmt, "repr": spec,
                                             "input_bytes": str(input_bytes), "status": "error: " + error}
    m = t.metrics
    return {"material": material, "format": fmt, "repr": spec, "describe": t.describe, "bytes": str(t.bytes),
            "input_bytes": str(input_bytes), "ratio": _num(input_bytes / t.bytes),
            "cos_rmse": _num(m.cos_rmse.mean), "cos_rmse_rel": _num(m.cos_rmse_rel.mean),
            "log_rmse": _num(m.log_rmse.mean), "cbrt_rmse": _num(m.cbrt_rmse.mean),
            "eval_pairs_per_s": _num(t.eval_rate), "build_s": _num(t.build_seconds),
            "status": "; ".join(["ok", *t.notes])}


def ok(row: Row) -> bool:
    return not row["status"].startswith("error")


def write_csv(rows: Sequence[Row], path: pathlib.Path, columns: Sequence[str] = COLUMNS) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def read_csv(path: pathlib.Path) -> List[Row]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = set(COLUMNS) - set(reader.fieldnames or [])
        if missing:
            raise ValueError(f"{path}: not a sweep CSV (no column {', '.join(sorted(missing))})")
        return list(reader)


class Bar:
    """A progress bar on stderr, "label  37% [#######.............] 12/32 what", rewritten in place on a
    terminal; elsewhere (logs) one line per finished step."""

    def __init__(self, label: str, total: int):
        self.label, self.total, self.done = label, max(total, 1), 0
        self.tty = sys.stderr.isatty()

    def _line(self, what: str) -> str:
        filled = 20 * self.done // self.total
        return (f"{self.label} {100 * self.done // self.total:3d}% [{'#' * filled}{'.' * (20 - filled)}]"
                f" {self.done}/{self.total} {what}")

    def show(self, what: str) -> None:
        if self.tty:
            sys.stderr.write("\r\033[K" + self._line(what))
            sys.stderr.flush()

    def step(self, what: str = "") -> None:
        self.done += 1
        if self.tty:
            self.show(what)
            if self.done >= self.total:
                sys.stderr.write("\n")
        else:
            sys.stderr.write(self._line(what) + "\n")
        sys.stderr.flush()


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


# --------------------------------------------------------------------------------------------- sweep

def sweep(files: Sequence[pathlib.Path], specs: Sequence[str], on_material=None) -> List[Row]:
    """trial() of every spec on every file, with a progress bar. on_material(name, brdf, rows, built)
    runs after each material with the Brdfs built for it (spec -> Brdf), before they are dropped."""
    rows: List[Row] = []
    bar = Bar("bench", len(files) * len(specs))
    for path in files:
        ref = brdfz.load(path)
        fmt, size, name = brdfz.format_of(str(path)), path.stat().st_size, path.stem
        built, mine = {}, []
        for spec in specs:
            bar.show(f"{name} {spec}")
            try:
                t = brdfz.trial(ref, spec)
                mine.append(trial_row(name, fmt, spec, size, t))
                built[spec] = t.brdf
            except ValueError as e:
                mine.append(trial_row(name, fmt, spec, size, error=str(e)))
            bar.step(f"{name} {spec}")
        rows += mine
        if on_material:
            on_material(name, ref, mine, built)
    return rows


def representatives(rows: Sequence[Row], count: int = 4) -> List[Row]:
    """Up to `count` settings spread along the material's size vs cos_rmse_rel Pareto front."""
    good = [r for r in rows if ok(r)]
    front = [good[i] for i in pareto_front([float(r["bytes"]) for r in good], [float(r["cos_rmse_rel"]) for r in good])]
    if len(front) <= count:
        return front
    return [front[round(k * (len(front) - 1) / (count - 1))] for k in range(count)]


# -------------------------------------------------------------------------------------------- charts

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


def _by_material(rows: Sequence[Row]) -> Dict[str, List[Row]]:
    out: Dict[str, List[Row]] = {}
    for r in rows:
        out.setdefault(r["material"], []).append(r)
    return out


def _finish(fig, handles_from, path: pathlib.Path) -> None:
    handles, labels = {}, {}
    for ax in handles_from:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=min(6, len(handles)),
               fontsize="small", frameon=False)
    fig.tight_layout(rect=(0, 0.04 + 0.02 * math.ceil(len(handles) / 6), 1, 1))
    fig.savefig(path, dpi=90)
    _plt().close(fig)


def chart_tradeoff(rows: Sequence[Row], x: str, y: str, path: pathlib.Path, *, maximize_x: bool = False) -> None:
    """One log-log panel per material: every ok setting coloured by method, the Pareto front joined
    and its points labelled."""
    by_mat = _by_material([r for r in rows if ok(r)])
    colours = _colours([method(r["repr"]) for r in rows])
    xlabel = {"bytes": "bytes", "eval_pairs_per_s": "eval pairs/s (one thread)"}[x]
    fig, axes = _panels(len(by_mat), f"{xlabel} vs {y}; Pareto front: black (errors < {ERROR_FLOOR:g} drawn at it)")
    for ax, (name, mine) in zip(axes, by_mat.items()):
        xs = [float(r[x]) for r in mine]
        ys = [max(float(r[y]), ERROR_FLOOR) for r in mine]
        for r, px, py in zip(mine, xs, ys):
            ax.scatter(px, py, color=colours[method(r["repr"])], label=method(r["repr"]), s=28, zorder=2)
        front = pareto_front(xs, ys, maximize_x=maximize_x)
        ax.plot([xs[i] for i in front], [ys[i] for i in front], "k-", lw=1, zorder=1, drawstyle="steps-post")
        ax.scatter([xs[i] for i in front], [ys[i] for i in front], facecolors="none", edgecolors="k", s=70, zorder=3)
        for i in front:
            ax.annotate(mine[i]["repr"].replace("tabular:", "").replace("analytic:", ""), (xs[i], ys[i]),
                        fontsize=6, xytext=(3, 3), textcoords="offset points")
        ax.set(xscale="log", yscale="log", title=name, xlabel=xlabel, ylabel=y)
        ax.grid(True, which="major", alpha=0.3)
    _finish(fig, axes, path)


def chart_auto(rows: Sequence[Row], auto: Sequence[Row], x: str, path: pathlib.Path) -> None:
    """Per material: each method's Pareto front (size or speed vs cos_rmse_rel) as a line, the
    representation brdfz.compress(auto=True) chose at each budget as a star."""
    by_mat = _by_material([r for r in rows if ok(r)])
    colours = _colours([method(r["repr"]) for r in rows])
    maximize_x = x == "eval_pairs_per_s"
    xlabel = {"bytes": "bytes", "eval_pairs_per_s": "eval pairs/s (one thread)"}[x]
    fig, axes = _panels(len(by_mat), f"auto-selected (cos_rmse_rel budgets: dotted) over each method's Pareto front")
    markers = "*PXD^v"
    budgets = sorted({a["budget"] for a in auto}, key=float)
    for ax, (name, mine) in zip(axes, by_mat.items()):
        for m in sorted({method(r["repr"]) for r in mine}):
            pts = [r for r in mine if method(r["repr"]) == m]
            xs = [float(r[x]) for r in pts]
            ys = [max(float(r["cos_rmse_rel"]), ERROR_FLOOR) for r in pts]
            front = pareto_front(xs, ys, maximize_x=maximize_x)
            ax.plot([xs[i] for i in front], [ys[i] for i in front], "-o", color=colours[m], ms=3, lw=1, alpha=0.6,
                    label=m)
        for a in auto:
            if a["material"] == name and a["chosen"]:
                k = budgets.index(a["budget"]) % len(markers)
                ax.scatter(float(a[x]), max(float(a["cos_rmse_rel"]), ERROR_FLOOR), marker=markers[k], s=160,
                           color="k", zorder=3, label=f"chosen at budget {a['budget']}")
                ax.annotate(a["chosen"], (float(a[x]), float(a["cos_rmse_rel"])), fontsize=6, xytext=(4, -9),
                            textcoords="offset points")
        for b in budgets:
            ax.axhline(float(b), color="grey", ls=":", lw=1)
        ax.set(xscale="log", yscale="log", title=name, xlabel=xlabel, ylabel="cos_rmse_rel")
        ax.grid(True, which="major", alpha=0.3)
    _finish(fig, axes, path)


# ------------------------------------------------------------------------------------------- renders

# The fixed lighting of every render: a directional light towards upper left front, and a sky that
# brightens upwards, sampled at fixed directions (a Fibonacci sphere, the same for every image).
LIGHT = np.array([-0.45, 0.55, 0.7]) / np.linalg.norm([-0.45, 0.55, 0.7])
LIGHT_IRRADIANCE = 2.0


def sky(d: np.ndarray) -> np.ndarray:
    up = d[:, 1:2]
    return np.where(up > 0, 0.25 + 0.35 * up, 0.12 + 0.05 * up) * np.array([0.85, 0.95, 1.1])


def fibonacci_sphere(n: int) -> np.ndarray:
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = k * math.pi * (3 - math.sqrt(5))
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _local(d: np.ndarray, t: np.ndarray, b: np.ndarray, n: np.ndarray) -> np.ndarray:
    return np.stack([(d * t).sum(1), (d * b).sum(1), (d * n).sum(1)], axis=1)


def render_sphere(brdf: brdfz.Brdf, size: int = 128, env_samples: int = 64) -> np.ndarray:
    """Radiance (size, size, 3) of an orthographic unit sphere seen along -z: at each pixel the normal
    gives the local frame (brdf.h: normal +z), wo is the view direction; the light contributes
    f·cosθi·E and each sky direction f·cosθi·L·4π/n. Black outside the sphere."""
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
    wi = _local(np.broadcast_to(LIGHT, n.shape), t, b, n)
    radiance = brdf.eval_cos(wi, wo) * LIGHT_IRRADIANCE
    dirs = fibonacci_sphere(env_samples)
    for d, L in zip(dirs, sky(dirs)):
        radiance += brdf.eval_cos(_local(np.broadcast_to(d, n.shape), t, b, n), wo) * L * (4 * math.pi / env_samples)
    image = np.zeros((size, size, 3))
    image[inside] = radiance
    return image


def tone_map(image: np.ndarray, exposure: float) -> np.ndarray:
    return np.clip(image * exposure, 0, 1) ** (1 / 2.2)


def render_material(name: str, ref: brdfz.Brdf, reps: Sequence[Row], built: Dict[str, brdfz.Brdf],
                    path: pathlib.Path, size: int, env_samples: int) -> None:
    """Reference and each representative setting (built again when not in `built`) side by side, the
    ×10 absolute error under each, all tone-mapped with the reference's exposure."""
    plt = _plt()
    reference = render_sphere(ref, size, env_samples)
    lum = reference.mean(axis=2)
    exposure = 0.8 / max(np.percentile(lum[lum > 0], 99) if (lum > 0).any() else 1.0, 1e-12)
    fig, axes = plt.subplots(2, len(reps) + 1, figsize=(2.4 * (len(reps) + 1), 5.3), squeeze=False)
    axes[0][0].imshow(tone_map(reference, exposure))
    axes[0][0].set_title(f"{name}\nreference", fontsize=8)
    axes[1][0].text(0.5, 0.5, "×10 |error|\n(same exposure)", ha="center", va="center", fontsize=8)
    for k, r in enumerate(reps, start=1):
        brdf = built.get(r["repr"]) or brdfz.compress(ref, r["repr"])
        image = render_sphere(brdf, size, env_samples)
        axes[0][k].imshow(tone_map(image, exposure))
        axes[0][k].set_title(f"{r['repr']}\n{int(r['bytes']):,} B, cos_rmse_rel {float(r['cos_rmse_rel']):.3g}",
                             fontsize=7)
        axes[1][k].imshow(tone_map(10 * np.abs(image - reference), exposure))
    for ax in axes.flat:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# ------------------------------------------------------------------------------------ auto selection

AUTO_COLUMNS = ["material", "budget", "chosen", "bytes", "cos_rmse_rel", "eval_pairs_per_s", "build_s", "tried"]


def auto_selection(materials: Dict[str, pathlib.Path], budgets: Sequence[float],
                   candidates: Optional[Sequence[str]]) -> List[Row]:
    """brdfz.compress(auto=True, metric="cos") on every material at every budget."""
    out = []
    bar = Bar("auto", len(materials) * len(budgets))
    for name, path in materials.items():
        ref = brdfz.load(path)
        for budget in budgets:
            bar.show(f"{name} budget {budget:g}")
            row = dict.fromkeys(AUTO_COLUMNS, "") | {"material": name, "budget": f"{budget:g}"}
            try:
                s = brdfz.compress(ref, auto=True, max_error=budget, metric="cos", candidates=candidates, report=True)
                c = s.candidates[s.chosen]
                row |= {"chosen": c.spec, "bytes": str(c.bytes), "cos_rmse_rel": _num(c.error),
                        "eval_pairs_per_s": _num(c.eval_rate), "build_s": _num(c.build_seconds),
                        "tried": str(len(s.candidates))}
            except ValueError as e:
                row["tried"] = str(len(e.selection.candidates)) if hasattr(e, "selection") else ""
            out.append(row)
            bar.step(f"{name} budget {budget:g}")
    return out


# ------------------------------------------------------------------------------------------- summary

def _table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def _g(v: str) -> str:
    return f"{float(v):.3g}" if v else ""


def smallest_within(rows: Sequence[Row], limit: float) -> Optional[Row]:
    fits = [r for r in rows if ok(r) and float(r["cos_rmse_rel"]) <= limit]
    return min(fits, key=lambda r: int(r["bytes"])) if fits else None


def _smallest_cells(rows: Sequence[Row], limit: float) -> List[str]:
    r = smallest_within(rows, limit)
    return [f"`{r['repr']}`", f"{int(r['bytes']):,}"] if r else ["none", ""]


def write_summary(out: pathlib.Path, rows: Sequence[Row], charts: Sequence[str], renders: Sequence[str],
                  auto: Sequence[Row], auto_charts: Sequence[str], source: str) -> pathlib.Path:
    by_mat = _by_material(rows)
    md = ["# brdfz compression benchmark\n",
          f"{len(by_mat)} materials × {len({r['repr'] for r in rows})} settings from {source}; "
          f"{datetime.date.today()}, {platform.node()} ({os.cpu_count()} CPUs, {platform.processor() or platform.machine()}). "
          "Errors are against each material's own data (cos_rmse_rel: cosine-weighted RMSE relative to the "
          "reference's RMS, channel mean); eval speed is batch eval on one thread. All rows: [sweep.csv](sweep.csv).\n",
          "## Smallest setting within an error\n",
          _table(["material", "≤ 2 % cos_rmse_rel", "bytes", "≤ 5 % cos_rmse_rel", "bytes"],
                 [[m, *_smallest_cells(mine, 0.02), *_smallest_cells(mine, 0.05)] for m, mine in by_mat.items()]),
          "## Size and speed against error\n"]
    md += [f"![{c}]({c})\n" for c in charts]
    md.append("## Pareto-optimal settings (bytes vs cos_rmse_rel)\n")
    for m, mine in by_mat.items():
        good = [r for r in mine if ok(r)]
        front = [good[i] for i in pareto_front([float(r["bytes"]) for r in good], [float(r["cos_rmse_rel"]) for r in good])]
        md += [f"### {m}\n", _table(["setting", "bytes", "ratio", "cos_rmse_rel", "log_rmse", "eval pairs/s", "build s"],
                                   [[f"`{r['repr']}`", f"{int(r['bytes']):,}", _g(r["ratio"]), _g(r["cos_rmse_rel"]),
                                     _g(r["log_rmse"]), _g(r["eval_pairs_per_s"]), _g(r["build_s"])] for r in front])]
    speeds: Dict[str, List[float]] = {}
    for r in rows:
        if ok(r):
            speeds.setdefault(method(r["repr"]), []).append(float(r["eval_pairs_per_s"]))
    md += ["## Eval speed per method (pairs/s, one thread, over materials and settings)\n",
           _table(["method", "median", "min", "max"],
                  [[m, f"{np.median(v):.3g}", f"{min(v):.3g}", f"{max(v):.3g}"] for m, v in sorted(speeds.items())])]
    if auto:
        md += ["## Budget-driven selection (`brdfz.compress(auto=True, metric=\"cos\")`)\n",
               _table(["material", "budget", "chosen", "bytes", "cos_rmse_rel", "eval pairs/s", "candidates tried"],
                      [[a["material"], a["budget"], f"`{a['chosen']}`" if a["chosen"] else "none within the budget",
                        f"{int(a['bytes']):,}" if a["bytes"] else "", _g(a["cos_rmse_rel"]),
                        _g(a["eval_pairs_per_s"]), a["tried"]] for a in auto])]
        md += [f"![{c}]({c})\n" for c in auto_charts]
    if renders:
        md.append("## Renders (reference, Pareto-optimal settings, ×10 error)\n")
        md += [f"![{r}]({r})\n" for r in renders]
    failed = [r for r in rows if not ok(r)]
    if failed:
        md += ["## Failed settings\n",
               _table(["material", "setting", "status"], [[r["material"], f"`{r['repr']}`", r["status"]] for r in failed])]
    path = out / "summary.md"
    path.write_text("\n".join(md))
    return path


# ---------------------------------------------------------------------------------------------- main

def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m brdfz.bench", description=__doc__.split("\n\n")[0])
    p.add_argument("--materials", nargs="+", metavar="DIR_OR_FILE", help="BRDF files or folders of them")
    p.add_argument("--specs", nargs="+", metavar="SPEC", help="settings (default: brdfz.benchmark_specs())")
    p.add_argument("--out", default="bench-out", help="output folder (default: bench-out)")
    p.add_argument("--quick", action="store_true", help="one setting per kind, small renders, one budget")
    p.add_argument("--from-csv", metavar="FILE", help="draw from this sweep CSV instead of sweeping")
    p.add_argument("--budgets", nargs="*", type=float, metavar="E",
                   help=f"cos_rmse_rel budgets of the auto selection (default {DEFAULT_BUDGETS}; none: skip it)")
    p.add_argument("--candidates", nargs="+", metavar="SPEC", help="auto selection candidates, cheapest first "
                                                                    "(default: brdfz.default_candidates())")
    p.add_argument("--render-size", type=int, help="sphere renders' size in pixels (default 128, --quick 64; 0: none)")
    args = p.parse_args(argv)

    started = time.monotonic()
    out = pathlib.Path(args.out)
    (out / "renders").mkdir(parents=True, exist_ok=True)
    files = material_files(args.materials) if args.materials else default_materials()
    if not files and not args.from_csv:
        p.error("no materials: ../shared/data/rgl and the MERL tables are missing; give --materials")
    specs = args.specs or (QUICK_SPECS if args.quick else brdfz.benchmark_specs())
    size = args.render_size if args.render_size is not None else (64 if args.quick else 128)
    env_samples = 32 if args.quick else 128
    budgets = args.budgets if args.budgets is not None else (DEFAULT_BUDGETS[1:] if args.quick else DEFAULT_BUDGETS)

    renders: List[str] = []

    def render(name, ref, mine, built):
        reps = representatives(mine)
        if size > 0 and reps:
            rel = f"renders/{name}.png"
            render_material(name, ref, reps, built, out / rel, size, env_samples)
            renders.append(rel)

    if args.from_csv:
        rows = read_csv(pathlib.Path(args.from_csv))
        by_stem = {f.stem: f for f in files}
        for name, mine in _by_material(rows).items():
            if name in by_stem:
                render(name, brdfz.load(by_stem[name]), mine, {})
        source = args.from_csv
    else:
        rows = sweep(files, specs, on_material=render)
        source = "python -m brdfz.bench"
    write_csv(rows, out / "sweep.csv")

    charts = []
    for metric in METRICS:
        chart_tradeoff(rows, "bytes", metric, out / f"size_vs_{metric}.png")
        charts.append(f"size_vs_{metric}.png")
    chart_tradeoff(rows, "eval_pairs_per_s", "cos_rmse_rel", out / "speed_vs_error.png", maximize_x=True)
    charts.append("speed_vs_error.png")

    materials = {f.stem: f for f in files if f.stem in {r["material"] for r in rows}}
    auto, auto_charts = [], []
    if budgets and materials:
        auto = auto_selection(materials, budgets, args.candidates)
        write_csv(auto, out / "auto.csv", AUTO_COLUMNS)
        for x, name in (("bytes", "auto_size_vs_error.png"), ("eval_pairs_per_s", "auto_speed_vs_error.png")):
            chart_auto(rows, auto, x, out / name)
            auto_charts.append(name)

    summary = write_summary(out, rows, charts, renders, auto, auto_charts, source)
    print(f"bench: {len(rows)} rows in {time.monotonic() - started:.0f} s")
    print(f"  table   {out / 'sweep.csv'}")
    print(f"  charts  {', '.join(str(out / c) for c in charts + auto_charts)}")
    if renders:
        print(f"  renders {out / 'renders'}/ ({len(renders)} materials)")
    print(f"  summary {summary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
