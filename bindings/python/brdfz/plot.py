"""Views of BRDFs for an analyst: each function is one call returning a matplotlib Figure, with several
materials or representations side by side, drawn from the library's eval (no BRDF maths here).

    import brdfz, brdfz.plot
    m = brdfz.load("paint.bsdf"); small = brdfz.compress(m, "svd:rank=4")
    brdfz.plot.polar({"measured": m, "svd": small}, theta_i=[20, 60]).savefig("polar.png")
    brdfz.plot.polar({"measured": m, "svd": small}, error="relative")    # svd against measured

`brdfs` is a Brdf, a sequence of them or a mapping {label: Brdf}. Angles are in degrees. `channel` is
"mean" (of r, g, b), "r", "g" or "b". With `error="signed"` (B − A) or `"relative"` ((B − A) / A) the
first material is the reference A and each other one is drawn as its error against A, masked (NaN)
where the reference's values are extrapolation: an incident elevation beyond its measured_theta_max
(RGL files). Needs matplotlib (pip install 'brdfz[plot]').
"""
from __future__ import annotations

import math
from typing import Callable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

import brdfz
from brdfz import report

Materials = Union[brdfz.Brdf, Sequence[brdfz.Brdf], Mapping[str, brdfz.Brdf]]
ERRORS = ("signed", "relative")
CHANNELS = ("mean", "r", "g", "b")


# ----------------------------------------------------------------------------------------- arguments

def _plt():
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("brdfz.plot needs matplotlib: pip install 'brdfz[plot]'") from None
    return plt


def _materials(brdfs: Materials) -> List[Tuple[str, brdfz.Brdf]]:
    """(label, Brdf) pairs: a mapping's keys, else each one's describe()."""
    if isinstance(brdfs, brdfz.Brdf):
        items = [("", brdfs)]
    elif isinstance(brdfs, Mapping):
        items = [(str(k), v) for k, v in brdfs.items()]
    elif isinstance(brdfs, Sequence) and not isinstance(brdfs, str):
        items = [("", v) for v in brdfs]
    else:
        raise TypeError(f"expected a brdfz.Brdf, a sequence or a mapping of them, got {type(brdfs).__name__}")
    if not items:
        raise ValueError("no materials to draw")
    for k, (name, b) in enumerate(items):
        if not isinstance(b, brdfz.Brdf):
            raise TypeError(f"material {name or k}: expected a brdfz.Brdf, got {type(b).__name__}")
    return [(name or _short(b.describe()), b) for name, b in items]


def _short(text: str, width: int = 40) -> str:
    """A default label: describe() cut to a panel's width (an analytic model lists every parameter)."""
    return text if len(text) <= width else text[:width - 1] + "…"


def _check(error: Optional[str], channel: str, count: int) -> None:
    if error is not None and error not in ERRORS:
        raise ValueError(f"error must be None, 'signed' or 'relative', not {error!r}")
    if error is not None and count < 2:
        raise ValueError("error: give the reference first and at least one material to compare with it")
    if channel not in CHANNELS:
        raise ValueError(f"channel must be one of {', '.join(CHANNELS)}, not {channel!r}")


def _degrees(values, name: str, low: float, high: float) -> np.ndarray:
    a = np.atleast_1d(np.asarray(values, dtype=float))
    if a.ndim != 1 or a.size == 0 or not np.isfinite(a).all() or (a < low).any() or (a > high).any():
        raise ValueError(f"{name}: expected finite angles in [{low:g}, {high:g}] degrees, got {values!r}")
    return a


def _positive(values: Sequence[np.ndarray]) -> np.ndarray:
    """The positive values of arrays, for a logarithmic scale's range; [1] when there is none."""
    positive = np.concatenate([v[v > 0] for v in values])
    return positive if positive.size else np.ones(1)


def _channel(f: np.ndarray, channel: str) -> np.ndarray:
    return f.mean(axis=-1) if channel == "mean" else f[..., "rgb".index(channel)]


def _elevation(v: np.ndarray) -> np.ndarray:
    """brdf.h's elevation of unit vectors, 2·asin(½‖v − ẑ‖)."""
    return 2 * np.arcsin(np.clip(0.5 * np.linalg.norm(v - [0.0, 0.0, 1.0], axis=-1), 0, 1))


def error_of(reference: np.ndarray, values: np.ndarray, kind: str, masked: np.ndarray) -> np.ndarray:
    """B − A or (B − A) / A, NaN where `masked` and (relative) where A is not positive."""
    if kind == "signed":
        e = values - reference
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            e = np.where(reference > 0, (values - reference) / np.where(reference > 0, reference, 1), np.nan)
    return np.where(masked, np.nan, e)


def _error_norm(kind: str, top: float):
    """A symmetric colour scale up to ±top: linear for signed errors; for relative ones logarithmic
    beyond ±1 %, as they span from a percent where the reference is bright to orders of magnitude
    where it is nearly 0."""
    from matplotlib.colors import Normalize, SymLogNorm

    if kind == "relative" and top > 0.01:
        return SymLogNorm(linthresh=0.01, vmin=-top, vmax=top, base=10)
    return Normalize(-top, top)


def _error_scale(ax, kind: str) -> None:
    """Relative error curves on a symmetric log axis beyond ±1 %, for the reason of _error_norm."""
    if kind == "relative":
        ax.set_yscale("symlog", linthresh=0.01)


def _error_label(kind: str) -> str:
    return "B − A (1/sr)" if kind == "signed" else "(B − A) / A"


def _grid(count: int, polar: bool = False, height: float = 3.6, layout=None):
    plt = _plt()
    cols = min(count, 4)
    rows = math.ceil(count / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, height * rows + 0.6), squeeze=False, layout=layout,
                             subplot_kw={"projection": "polar"} if polar else None)
    for ax in axes.flat[count:]:
        ax.set_visible(False)
    return fig, list(axes.flat[:count])


# ----------------------------------------------------------------------------------------------- polar

def plane_directions(theta_i: float, plane: float, angles: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """wi at elevation theta_i (azimuth 0) and wo at the signed elevations `angles` in the plane at
    azimuth `plane` from the incidence plane (degrees): positive angles on the far side from the light
    (the mirror direction of wi is at +theta_i in the incidence plane, plane=0), negative ones towards it."""
    wi = brdfz.directions(math.radians(theta_i), 0.0)
    a = np.radians(angles)
    wo = brdfz.directions(np.abs(a), np.where(a > 0, math.radians(plane) + math.pi, math.radians(plane)))
    return wi, wo


def _in_plane(m: brdfz.Measurements, theta_i: float, plane: float, tolerance: float):
    """The measurements with θi within `tolerance` of theta_i and wo within it of the plane (rotated
    about the normal so that wi has azimuth 0: isotropy assumed): their signed in-plane angles and values."""
    ti = np.degrees(_elevation(m.wi))
    to = np.degrees(_elevation(m.wo))
    dphi = np.degrees(np.arctan2(m.wo[:, 1], m.wo[:, 0]) - np.arctan2(m.wi[:, 1], m.wi[:, 0]))

    def near(a, b):  # azimuths a, b within the tolerance, modulo 360, or wo within it of the normal
        return (np.abs((a - b + 180) % 360 - 180) <= tolerance) | (to <= tolerance)

    pick = np.abs(ti - theta_i) <= tolerance
    far, towards = pick & near(dphi, plane + 180), pick & near(dphi, plane) & ~near(dphi, plane + 180)
    sel = far | towards
    return np.where(far, to, -to)[sel], m.f[sel]


def polar(brdfs: Materials, theta_i: Sequence[float] = (0, 30, 60), *, plane: float = 0.0, channel: str = "mean",
          log: bool = False, error: Optional[str] = None, measurements: Optional[brdfz.Measurements] = None,
          tolerance: float = 5.0, samples: int = 181):
    """f_r in a plane of outgoing directions at each incidence `theta_i` (degrees), one polar panel per
    material: the plane at azimuth `plane` from the incidence plane (0: the incidence plane, the light
    drawn as a star on the left and the mirror direction on the right; 90: the perpendicular plane),
    θo signed from the normal, `samples` of them over ±89.5°. log=True: a logarithmic radius.
    `measurements` (load_measurements()) within `tolerance` degrees of each incidence and of the plane
    are drawn as dots over every panel. With `error`, Cartesian panels of each material's error
    against the first along the same θo."""
    items = _materials(brdfs)
    _check(error, channel, len(items))
    theta_i = _degrees(theta_i, "theta_i", 0, 89.9)
    if not (isinstance(samples, int) and samples >= 3):
        raise ValueError(f"samples must be an integer >= 3, not {samples!r}")
    if not math.isfinite(plane):
        raise ValueError(f"plane must be a finite azimuth in degrees, not {plane!r}")
    # The horizon itself is left out: f_r is 0 there by convention, and a file's values next to it are
    # divided by a vanishing cosine (RGL files).
    angles = np.linspace(-89.5, 89.5, samples)
    wo = plane_directions(0.0, plane, angles)[1]
    wi = brdfz.directions(np.radians(theta_i), 0.0)
    values = [_channel(b.eval(wi[:, None, :], wo[None, :, :]), channel) for _, b in items]
    colours = _plt().get_cmap("viridis")(np.linspace(0, 0.85, len(theta_i)))
    in_plane = "incidence plane" if plane % 180 == 0 else f"plane at {plane:g}° from the incidence plane"

    if error:
        (ref_name, ref), rest = items[0], items[1:]
        fig, axes = _grid(len(rest))
        masked = np.radians(theta_i)[:, None] > ref.measured_theta_max
        for ax, (name, _), v in zip(axes, rest, values[1:]):
            e = error_of(values[0], v, error, np.broadcast_to(masked, v.shape))
            for k, t in enumerate(theta_i):
                label = f"θi = {t:g}°" + (" (beyond measured: masked)" if masked[k, 0] else "")
                ax.plot(angles, e[k], color=colours[k], label=label)
            ax.axhline(0, color="grey", lw=0.8)
            ax.set(xlabel=f"θo in the {in_plane} (°, + away from the light)", ylabel=_error_label(error),
                   xlim=(-90, 90))
            ax.set_title(f"{name}\nagainst {ref_name}", fontsize="small")
            _error_scale(ax, error)
            ax.legend(fontsize="x-small")
        fig.tight_layout()
        return fig

    fig, axes = _grid(len(items), polar=True)
    for ax, (name, _), v in zip(axes, items, values):
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)  # clockwise from the normal: positive θo on the right
        ax.set_thetamin(-90)
        ax.set_thetamax(90)
        for k, t in enumerate(theta_i):
            ax.plot(np.radians(angles), v[k], color=colours[k], label=f"θi = {t:g}°")
        if log:
            positive = _positive(values)
            ax.set_rscale("log")
            ax.set_rlim(max(positive.min(), positive.max() * 1e-4), positive.max() * 1.5)
        if measurements is not None:
            for k, t in enumerate(theta_i):
                a, f = _in_plane(measurements, t, plane, tolerance)
                ax.scatter(np.radians(a), _channel(f, channel), s=9, color=colours[k], edgecolors="k",
                           linewidths=0.4, zorder=3, label="measured" if k == 0 else None)
        if plane % 180 == 0:
            edge = ax.get_rmax()
            for k, t in enumerate(theta_i):
                ax.plot([math.radians(-t)], [edge], marker="*", ms=11, color=colours[k], clip_on=False, zorder=4,
                        label="light" if k == 0 else None)
        ax.set_title(f"{name}\nf_r ({channel}, 1/sr) in the {in_plane}", fontsize="small")
        ax.legend(fontsize="x-small", loc="lower left", bbox_to_anchor=(-0.1, -0.15))
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------- slices

def _image_panels(items, grids, extent, labels, error, ref_mask, log, title, channel):
    """Images of f_r (or errors against the first) on a (rows, cols, 3) grid of pairs per material."""
    plt = _plt()
    from matplotlib.colors import LogNorm, Normalize

    wi, wo = grids
    values = [_channel(b.eval(wi, wo), channel) for _, b in items]
    if error:
        shown = [(f"{n}\nagainst {items[0][0]}", error_of(values[0], v, error, ref_mask))
                 for (n, _), v in zip(items[1:], values[1:])]
        finite = np.concatenate([np.abs(e[np.isfinite(e)]) for _, e in shown] + [np.zeros(1)])
        # One scale for every panel, so that representations compare; the 99.5th percentile keeps a
        # few extreme bins from washing the rest out.
        top = float(np.percentile(finite, 99.5)) or 1.0
        norm, cmap, label = _error_norm(error, top), "RdBu_r", _error_label(error)
    else:
        shown = [(n, v) for (n, _), v in zip(items, values)]
        positive = _positive(values)
        # The 99.5th percentile: values next to grazing angles (an RGL file's, divided by a vanishing
        # cosine) would otherwise leave the rest of the image black.
        top = float(np.percentile(positive, 99.5))
        norm = LogNorm(max(float(positive.min()), top * 1e-4), top) if log else Normalize(0, top)
        cmap, label = "inferno", f"f_r ({channel}, 1/sr)"
    # Constrained: the shared colour bar, the figure's title and two-line panel titles kept apart.
    fig, axes = _grid(len(shown), height=3.4, layout="constrained")
    for ax, (name, image) in zip(axes, shown):
        data = np.ma.masked_invalid(image)
        if log and not error:
            data = np.ma.masked_less_equal(data, 0)
        im = ax.imshow(data, origin="lower", extent=extent, aspect="auto", cmap=cmap, norm=norm,
                       interpolation="nearest")
        ax.set(title=name, xlabel=labels[0], ylabel=labels[1])
        ax.title.set_fontsize("small")
    fig.colorbar(im, ax=axes, label=label, shrink=0.9, extend="both" if error else "max")
    fig.suptitle(title, fontsize="medium")
    return fig


def _check_res(res, name):
    if not (isinstance(res, int) and 2 <= res <= 4096):
        raise ValueError(f"{name} must be an integer in [2, 4096], not {res!r}")


def _half_diff_grid(rows: np.ndarray, cols: np.ndarray, *, theta_h, theta_d, phi_d):
    """Direction pairs (wi, wo) of shape (len(rows), len(cols), 3) at Rusinkiewicz angles in degrees:
    each of theta_h, theta_d, phi_d is "rows", "cols" or one angle."""
    def angle(value):
        if isinstance(value, str):
            return np.radians(rows)[:, None] if value == "rows" else np.radians(cols)[None, :]
        return math.radians(value)

    return brdfz.from_half_diff(angle(theta_h), angle(theta_d), angle(phi_d))


def theta_h_theta_d(brdfs: Materials, *, phi_d: float = 90.0, res: int = 90, log: bool = True,
                    channel: str = "mean", error: Optional[str] = None):
    """Images of f_r over θh (x) and θd (y), both over [0, 90°) at `res` bin centres, at the azimuth
    `phi_d` (degrees); one panel per material, one colour scale (log=True: logarithmic; pairs below
    the horizon are 0, left blank). With `error`, each material's error against the first."""
    items = _materials(brdfs)
    _check(error, channel, len(items))
    _check_res(res, "res")
    _degrees(phi_d, "phi_d", -360, 360)
    axis = (np.arange(res) + 0.5) * 90 / res
    wi, wo = _half_diff_grid(axis, axis, theta_h="cols", theta_d="rows", phi_d=phi_d)
    mask = _elevation(wi) > items[0][1].measured_theta_max
    return _image_panels(items, (wi, wo), (0, 90, 0, 90), ("θh (°)", "θd (°)"), error, mask, log,
                         f"θh × θd at φd = {phi_d:g}°", channel)


def theta_h_phi_d(brdfs: Materials, *, theta_d: float = 30.0, res: Tuple[int, int] = (90, 180), log: bool = True,
                  channel: str = "mean", error: Optional[str] = None):
    """Images of f_r over θh (x, [0, 90°)) and φd (y, [0, 360°): non-reciprocal data differs between φd
    and φd + 180°) at the difference elevation `theta_d` (degrees), as theta_h_theta_d."""
    items = _materials(brdfs)
    _check(error, channel, len(items))
    if not (isinstance(res, (tuple, list)) and len(res) == 2):
        raise ValueError(f"res must be (theta_h bins, phi_d bins), not {res!r}")
    _check_res(res[0], "res[0]")
    _check_res(res[1], "res[1]")
    _degrees(theta_d, "theta_d", 0, 90)
    th = (np.arange(res[0]) + 0.5) * 90 / res[0]
    pd = (np.arange(res[1]) + 0.5) * 360 / res[1]
    wi, wo = _half_diff_grid(pd, th, theta_h="cols", theta_d=theta_d, phi_d="rows")
    mask = _elevation(wi) > items[0][1].measured_theta_max
    return _image_panels(items, (wi, wo), (0, 90, 0, 360), ("θh (°)", "φd (°)"), error, mask, log,
                         f"θh × φd at θd = {theta_d:g}°", channel)


# ----------------------------------------------------------------------------------------------- albedo

def albedo(brdfs: Materials, theta: Optional[Sequence[float]] = None, *, channel: str = "mean",
           error: Optional[str] = None):
    """Directional albedo ρ(θo) = ∫ f cosθi dωi (brdfz.albedo) against θo (degrees, default 0 to 89),
    every material on one axes. With `error`, each material's error against the first, masked beyond
    the first's measured elevation (by reciprocity, where the reference rests on extrapolated data)."""
    items = _materials(brdfs)
    _check(error, channel, len(items))
    theta = np.arange(0.0, 90.0) if theta is None else _degrees(theta, "theta", 0, 89.99)
    values = [_channel(brdfz.albedo(b, np.radians(theta)), channel) for _, b in items]
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    if error:
        masked = np.radians(theta) > items[0][1].measured_theta_max
        for (name, _), v in zip(items[1:], values[1:]):
            ax.plot(theta, error_of(values[0], v, error, masked), label=name)
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(ylabel=f"albedo {_error_label(error).replace(' (1/sr)', '')}", title=f"albedo against {items[0][0]}")
        _error_scale(ax, error)
    else:
        for (name, _), v in zip(items, values):
            ax.plot(theta, v, label=name)
        ax.set(ylabel=f"directional albedo ({channel})", ylim=(0, None))
    ax.set(xlabel="θo (°)", xlim=(0, 90))
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------- sphere

def sphere(brdfs: Materials, *, size: int = 128, samples: int = 64, light: Sequence[float] = tuple(report.LIGHT),
           irradiance: float = report.LIGHT_IRRADIANCE, environment: Callable = report.sky,
           exposure: Optional[float] = None, error: Optional[str] = None, seed: int = 1):
    """Spheres lit by a sun (direction `light`, world frame: x right, y up, z towards the viewer, of
    `irradiance`) and an environment (radiance of world directions, (N, 3) -> (N, 3)), rendered by
    report.render_sphere (the environment importance-sampled with each material's own sampler,
    `samples` per pixel), tone-mapped at one exposure (default: the first's 99th percentile). With
    `error`, the images' error against the first (mean channel, one colour scale, pixels whose sun
    elevation is beyond the first's measured elevation masked)."""
    items = _materials(brdfs)
    _check(error, "mean", len(items))
    images = [report.render_sphere(b, size, samples, light=light, irradiance=irradiance, environment=environment,
                                   seed=seed) for _, b in items]
    plt = _plt()
    if error:
        ref = images[0].mean(axis=2)
        mask = sun_elevation(size, light) > items[0][1].measured_theta_max
        shown = [(f"{n}\nagainst {items[0][0]}", error_of(ref, im.mean(axis=2), error, mask | (ref == 0)))
                 for (n, _), im in zip(items[1:], images[1:])]
        finite = np.concatenate([np.abs(e[np.isfinite(e)]) for _, e in shown] + [np.zeros(1)])
        top = float(np.percentile(finite, 99.5)) or 1.0
        fig, axes = _grid(len(shown), height=3.6)
        for ax, (name, e) in zip(axes, shown):
            im = ax.imshow(np.ma.masked_invalid(e), cmap="RdBu_r", norm=_error_norm(error, top))
            ax.set_title(name, fontsize="small")
            ax.axis("off")
        fig.colorbar(im, ax=axes, label=_error_label(error).replace("1/sr", "radiance"), shrink=0.9)
        return fig
    if exposure is None:
        exposure = report.exposure_of(images[0])
    fig, axes = _grid(len(items), height=3.6)
    for ax, (name, _), im in zip(axes, items, images):
        ax.imshow(report.tone_map(im, exposure))
        ax.set_title(name, fontsize="small")
        ax.axis("off")
    fig.tight_layout()
    return fig


def sun_elevation(size: int, light: Sequence[float]) -> np.ndarray:
    """The sun's elevation (radians) in each pixel's local frame of render_sphere's sphere (π/2 outside)."""
    u = (np.arange(size) + 0.5) / size * 2 - 1
    x, y = np.meshgrid(u, -u)
    n = np.stack([x, y, np.sqrt(np.clip(1 - x * x - y * y, 0, None))], axis=-1)
    d = np.asarray(light, float) / np.linalg.norm(light)
    return np.where(x * x + y * y < 1, 2 * np.arcsin(np.clip(0.5 * np.linalg.norm(n - d, axis=-1), 0, 1)), math.pi / 2)
