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

Two implementations behind one interface:
- native (tables, compact tables, factored, PCA and analytic models, in the JIT variants llvm_ad_rgb
  and cuda_ad_rgb): the representation's arrays become Dr.Jit arrays and its eval, pdf and sampler
  are Dr.Jit code (brdfz/_native: the C++ functions ported operation by operation, in double
  precision like them, on the C++ sampler's own tables), so Mitsuba traces them into its kernels in
  its default symbolic (megakernel) mode, any number of materials in a scene, and differentiates
  through them: mi.traverse() lists the differentiable arrays (`values` of a table, `lut` or
  `half_scales` of a compact one, `u`, `v`, `colour_weights` of factors, `coefficients` of a PCA
  material, `params` of an analytic model). Sampling keeps the tables of the Brdf it was built from.
- wavefront (every other kind: RGL-EPFL files, φh stacks, scattered measurements; scalar variants; or
  native=False): each call hands its lanes to brdfz's C++ batch kernels through numpy. It cannot be
  traced into a kernel, so building one switches Dr.Jit's symbolic loops and calls off for the process
  (wavefront mode, one batch per bounce); while one exists, symbolic mode must stay off (a symbolic
  call traces every live BSDF), and Mitsuba's differentiable integrators (`prb`), which need it, do
  not run. Scalar variants work too, one pair per call. Not differentiable.
Spectral, monochrome and polarised variants are not supported (brdfz materials are RGB): ValueError.
"""
from __future__ import annotations

from typing import Optional

import drjit as dr
import mitsuba as mi
import numpy as np

from . import Brdf, load
from ._native import Model, Unsupported
from ._native._bsdf import bsdf_class

_classes: dict = {}  # the wavefront class per variant


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
        """A brdfz Brdf as a Mitsuba BSDF through numpy (module docstring: conventions)."""

        def __init__(self, props: mi.Properties, brdf: Brdf, incident: str):
            mi.BSDF.__init__(self, props)
            _use_wavefront_mode()
            self.brdf = brdf
            self.camera = incident == "camera"
            self.m_components = [mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def _enabled(self, ctx) -> bool:
            return ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        def _value(self, view: np.ndarray, light: np.ndarray) -> np.ndarray:
            """f·cosθ(light), brdfz's wi at the camera side (the default) or at the light."""
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


def _check_variant() -> None:
    variant = mi.variant()
    if variant is None:
        raise ValueError("brdfz.mitsuba: set a Mitsuba variant first (mi.set_variant)")
    if not mi.is_rgb or mi.is_polarized:
        raise ValueError(f"brdfz.mitsuba: variant {variant!r} is not supported: brdfz materials are RGB "
                         "(use llvm_ad_rgb, cuda_ad_rgb or scalar_rgb)")


def _make(brdf: Brdf, incident: str, native: Optional[bool], props: Optional["mi.Properties"] = None) -> "mi.BSDF":
    _check_variant()
    props = mi.Properties() if props is None else props
    if incident not in ("light", "camera"):
        raise ValueError(f"brdfz BSDF: incident must be 'light' or 'camera', not {incident!r}")
    if native is not False:
        if not dr.is_jit_v(mi.Float):
            if native:
                raise ValueError(f"brdfz.mitsuba: the native bridge needs a JIT variant (llvm_ad_rgb, cuda_ad_rgb), "
                                 f"not {mi.variant()!r}")
        else:
            try:
                return bsdf_class()(props, Model(brdf), incident)
            except Unsupported as e:
                if native:
                    raise ValueError(f"brdfz.mitsuba: no native port for {e} (RGL files and scattered "
                                     "measurements take the wavefront bridge: native=None or False)") from None
    return _class()(props, brdf, incident)


def register(name: str = "brdfz") -> None:
    """Registers the plugin `name` for the current Mitsuba variant: {"type": name, "filename": PATH,
    "lookup": "linear" | "nearest", "incident": "light" | "camera", "native": bool (optional)} loads
    PATH with brdfz.load and makes it a BSDF as bsdf() does."""
    _check_variant()

    def plugin(props: "mi.Properties") -> "mi.BSDF":
        if "filename" not in props:
            raise ValueError("brdfz BSDF: give 'filename' (a file brdfz.load reads)")
        brdf = load(str(props["filename"]), lookup=props.get("lookup", "linear"))
        return _make(brdf, props.get("incident", "camera"), props.get("native", None), props)

    mi.register_bsdf(name, plugin)


def bsdf(brdf: Brdf, incident: str = "camera", native: Optional[bool] = None) -> "mi.BSDF":
    """A Mitsuba BSDF backed by `brdf` (any representation), to place in a scene dictionary;
    `incident` says which side brdfz's wi is evaluated at (module docstring). native=None: Dr.Jit code
    where the kind and variant allow, the wavefront bridge otherwise; True: native or ValueError;
    False: the wavefront bridge. TypeError for anything but a Brdf."""
    if not isinstance(brdf, Brdf):
        raise TypeError(f"brdfz.mitsuba.bsdf: expected a brdfz.Brdf, got {type(brdf).__name__}")
    return _make(brdf, incident, native)
