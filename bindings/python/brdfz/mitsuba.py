"""Mitsuba 3 bridge: any brdfz Brdf as a Mitsuba BSDF, so scenes render measured and compressed
materials.

    import mitsuba as mi, brdfz, brdfz.mitsuba
    mi.set_variant("llvm_ad_rgb")
    brdfz.mitsuba.register()                       # plugin "brdfz": {"type": "brdfz", "filename": ...}
    material = brdfz.mitsuba.bsdf(brdfz.compress(brdfz.load("x.bsdf"), "analytic:lambert+ggx"))
    scene = mi.load_dict({..., "shape": {"type": "sphere", "bsdf": material}})

Conventions. Mitsuba's BSDFs work in the local shading frame (normal +z) with ``si.wi`` pointing to
where the light leaves (the camera, in a path tracer) and ``wo`` the direction they evaluate and
sample (towards the light); ``eval`` and the sample weight include cosθ of ``wo``. brdfz's ``wi`` is
the incident light direction and ``wo`` the outgoing one (brdf.h), hence
    eval(si, wo)          = Brdf.eval_cos(wi=wo, wo=si.wi)      f·cosθ(wo)
    pdf(si, wo)           = Brdf.pdf(wo=si.wi, wi=wo)
    sample(si, _, u) -> (bs.wo, bs.pdf, weight) = Brdf.sample(wo=si.wi, u)   weight = f·cosθ(bs.wo)/pdf
The BSDF is one glossy reflection lobe on the front side; below the horizon it is black.

Measured data are not exactly reciprocal, and Mitsuba's own `measured` plugin reads an RGL-EPFL
file's incident direction (brdfz's wi for that file, rgl.h) at si.wi, the camera side. With
incident="camera" the bridge does the same: eval = Brdf.eval(wi=si.wi, wo=wo)·cosθ(wo), sampled
directions still come from Brdf.sample(wo=si.wi, u) (the same draws, so pdf is unchanged) and their
weight is that eval over pdf. For a reciprocal BRDF both settings agree. "camera" is the default:
it is Mitsuba's own convention (its `incident` si.wi), so RGL files render as `measured` renders them
(the files' adaptive parameterisation is sharp around the incident side it was built for); "light"
applies the data with the incident light at wi, as brdf.h reads a pair.

Each call hands the lanes to brdfz's batch kernels through numpy, so the plugin cannot be traced
into a Dr.Jit kernel: in JIT variants (llvm_*) register() and bsdf() switch Dr.Jit's symbolic loops
and calls off (wavefront mode), which is also what makes those variants fast here, one batch per
bounce. Scalar variants work too, one direction pair per call. Differentiation is not supported.
"""
from __future__ import annotations

from typing import Optional

import drjit as dr
import mitsuba as mi
import numpy as np

from . import Brdf, load

_classes: dict = {}


def _use_wavefront_mode() -> None:
    if dr.is_jit_v(mi.Float):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _rows(v, n: int) -> np.ndarray:
    """A Mitsuba 3-vector (one lane or n) as an (n, 3) float64 array."""
    a = np.asarray(v, dtype=np.float64).reshape(3, -1).T
    return np.broadcast_to(a, (n, 3)) if a.shape[0] != n else a


def _lanes(active, n: int) -> np.ndarray:
    return np.broadcast_to(np.asarray(active, dtype=bool).reshape(-1), (n,))


def _directions(v, active, n: int) -> np.ndarray:
    """Rows of v, with inactive or degenerate lanes replaced by a direction below the horizon, where
    brdfz returns 0 (Mitsuba leaves garbage in inactive lanes; brdfz rejects non-finite rows)."""
    d = np.array(_rows(v, n))
    bad = ~_lanes(active, n) | ~np.isfinite(d).all(axis=1) | ~(np.abs(d).sum(axis=1) > 0)
    d[bad] = (0.0, 0.0, -1.0)
    return d


def _width(*values) -> int:
    return max(dr.width(v) for v in values)


def _class():
    """The BSDF class for the current variant (mi.BSDF differs per variant)."""
    variant = mi.variant()
    if variant in _classes:
        return _classes[variant]
    scalar = not dr.is_jit_v(mi.Float)

    def color(a: np.ndarray):
        a = a.astype(np.float32)
        return mi.Color3f(*a[0]) if scalar else mi.Color3f(np.ascontiguousarray(a.T))

    def floats(a: np.ndarray):
        a = a.astype(np.float32)
        return mi.Float(a[0]) if scalar else mi.Float(a)

    def vector(a: np.ndarray):
        a = a.astype(np.float32)
        return mi.Vector3f(*a[0]) if scalar else mi.Vector3f(np.ascontiguousarray(a.T))

    class BrdfzBSDF(mi.BSDF):
        """A brdfz Brdf as a Mitsuba BSDF (module docstring: conventions)."""

        def __init__(self, props: mi.Properties, brdf: Optional[Brdf] = None, incident: str = "camera"):
            mi.BSDF.__init__(self, props)
            if brdf is None:
                if "filename" not in props:
                    raise ValueError("brdfz BSDF: give 'filename' (a file brdfz.load reads)")
                brdf = load(str(props["filename"]), lookup=props.get("lookup", "linear"))
                incident = props.get("incident", incident)
            if incident not in ("light", "camera"):
                raise ValueError(f"brdfz BSDF: incident must be 'light' or 'camera', not {incident!r}")
            self.brdf = brdf
            self.camera = incident == "camera"
            self.m_components = [mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def _enabled(self, ctx) -> bool:
            return ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        def _value(self, view: np.ndarray, light: np.ndarray) -> np.ndarray:
            """f·cosθ(light), brdfz's wi at the light (default) or at the camera side."""
            if self.camera:
                return self.brdf.eval(view, light) * np.maximum(light[:, 2:3], 0.0)
            return self.brdf.eval_cos(light, view)

        def eval(self, ctx, si, wo, active=True):
            n = _width(si.wi, wo)
            if not self._enabled(ctx):
                return dr.zeros(mi.Color3f, n)
            return color(self._value(_directions(si.wi, active, n), _directions(wo, active, n)))

        def pdf(self, ctx, si, wo, active=True):
            n = _width(si.wi, wo)
            if not self._enabled(ctx):
                return dr.zeros(mi.Float, n)
            return floats(self.brdf.pdf(_directions(si.wi, active, n), _directions(wo, active, n)))

        def eval_pdf(self, ctx, si, wo, active=True):
            n = _width(si.wi, wo)
            if not self._enabled(ctx):
                return dr.zeros(mi.Color3f, n), dr.zeros(mi.Float, n)
            view, light = _directions(si.wi, active, n), _directions(wo, active, n)
            return color(self._value(view, light)), floats(self.brdf.pdf(view, light))

        def sample(self, ctx, si, sample1, sample2, active=True):
            n = _width(si.wi, sample2)
            bs = dr.zeros(mi.BSDFSample3f, n)
            if not self._enabled(ctx):
                return bs, dr.zeros(mi.Color3f, n)
            u = np.asarray(sample2, dtype=np.float64).reshape(2, -1).T
            u = np.broadcast_to(u, (n, 2)) if u.shape[0] != n else u
            view = _directions(si.wi, active, n)
            wi, pdf, weight = self.brdf.sample(view, u)
            if self.camera:
                drawn = pdf > 0
                weight[drawn] = self._value(view[drawn], wi[drawn]) / pdf[drawn, None]
            bs.wo = vector(wi)
            bs.pdf = floats(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, color(weight)

        def to_string(self) -> str:
            return f"BrdfzBSDF[{self.brdf.describe()}]"

    _classes[variant] = BrdfzBSDF
    return BrdfzBSDF


def register(name: str = "brdfz") -> None:
    """Registers the plugin `name` for the current Mitsuba variant: {"type": name, "filename": PATH,
    "lookup": "linear" | "nearest", "incident": "light" | "camera"} loads PATH with brdfz.load."""
    _use_wavefront_mode()
    cls = _class()
    mi.register_bsdf(name, lambda props: cls(props))


def bsdf(brdf: Brdf, incident: str = "camera") -> "mi.BSDF":
    """A Mitsuba BSDF backed by `brdf` (any representation), to place in a scene dictionary;
    `incident` says which side brdfz's wi is evaluated at (module docstring). TypeError for anything
    but a Brdf."""
    if not isinstance(brdf, Brdf):
        raise TypeError(f"brdfz.mitsuba.bsdf: expected a brdfz.Brdf, got {type(brdf).__name__}")
    _use_wavefront_mode()
    return _class()(mi.Properties(), brdf, incident)
