"""The native bridge's Mitsuba BSDF: a Model (this package) behind mi.BSDF's interface, with the
conventions of brdfz.mitsuba's docstring (si.wi the camera side; eval and weights include cosθ(wo);
incident="camera" reads brdfz's wi at si.wi). Everything is Dr.Jit code, so Mitsuba traces it into
its kernels in any mode (symbolic megakernels by default) and differentiates through it."""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import Model
from ._math import directions, f32, f64

_classes: dict = {}


def bsdf_class():
    """The class for the current variant (mi.BSDF differs per variant)."""
    variant = mi.variant()
    cls = _classes.get(variant)
    if cls is not None:
        return cls

    class NativeBrdfzBSDF(mi.BSDF):
        """A brdfz Brdf as Dr.Jit code (brdfz.mitsuba: conventions)."""

        def __init__(self, props: mi.Properties, model: Model, incident: str):
            mi.BSDF.__init__(self, props)
            self.model = model
            self.camera = incident == "camera"
            self.m_components = [mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def _value(self, view, light):
            """f·cosθ(light) with brdfz's wi at the camera side or at the light."""
            f = self.model.eval(view, light) if self.camera else self.model.eval(light, view)
            c = dr.maximum(light[2], 0.0)
            return tuple(x * c for x in f)

        @staticmethod
        def _color(f, active):
            return dr.select(active, mi.Color3f(f32(f[0]), f32(f[1]), f32(f[2])), 0.0)

        def eval(self, ctx, si, wo, active=True):
            view, ok_v = directions(si.wi, active)
            light, ok_l = directions(wo, active)
            on = ok_v & ok_l & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)
            return self._color(self._value(view, light), on)

        def pdf(self, ctx, si, wo, active=True):
            view, ok_v = directions(si.wi, active)
            light, ok_l = directions(wo, active)
            on = ok_v & ok_l & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)
            return dr.select(on, f32(self.model.pdf(view, light)), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            view, ok_v = directions(si.wi, active)
            light, ok_l = directions(wo, active)
            on = ok_v & ok_l & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)
            return self._color(self._value(view, light), on), dr.select(on, f32(self.model.pdf(view, light)), 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            view, ok_v = directions(si.wi, active)
            on = ok_v & ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)
            wi, pdf, drawn = self.model.sample(view, f64(sample2[0]), f64(sample2[1]), on)
            f = self._value(view, wi)
            inv = dr.select(drawn, 1.0 / pdf, 0.0)
            bs = mi.BSDFSample3f()
            bs.wo = mi.Vector3f(f32(wi[0]), f32(wi[1]), f32(wi[2]))
            bs.pdf = f32(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, self._color(tuple(x * inv for x in f), drawn)

        def traverse(self, callback):
            for name, value in self.model.params().items():
                callback.put(name, value, mi.ParamFlags.Differentiable)

        def parameters_changed(self, keys):
            self.model.parameters_changed()

        def to_string(self) -> str:
            return f"NativeBrdfzBSDF[{self.model.describe}]"

    _classes[variant] = NativeBrdfzBSDF
    return NativeBrdfzBSDF
