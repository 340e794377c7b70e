"""brdfz representations as Dr.Jit code, for the native Mitsuba 3 bridge (brdfz.mitsuba).

A Model holds a representation's stored arrays as Dr.Jit arrays of the current variant (from
Brdf.parts()) and its sampler's tables (Brdf.sampler_parts(): the compact sampler, or the fine
half-vector one), and evaluates, samples and returns
pdfs with brdf.h's conventions on unit Float64 direction tuples: the same functions as the C++
library, ported operation by operation, traced into Mitsuba's kernels. Kinds: tabular (f32),
compact tables (f16, u8log), factored (svd, nmf), PCA and analytic models, on grids folded by
reciprocity, over the full φd circle (symmetry=none) or folded by the mirror (symmetry=bilateral).
Anything else (φh stacks, RGL files, scattered measurements) raises Unsupported, and the bridge takes
its wavefront path.

Differentiable arrays (params()): a table's values, a u8log table's decoding table or a float16
table's channel scales, the factors and colour weights, PCA coefficients, analytic parameters.
Sampling tables stay those of the Brdf the model was built from: after the parameters change the
draws are those of the original representation and pdf stays the density they are drawn from.
"""
from __future__ import annotations

import numpy as np
import drjit as dr
import mitsuba as mi

from ._compact import CompactSampler
from ._halfvector import HalfVectorSampler
from ._lobes import AnalyticModel
from ._math import F64, u32
from ._tables import (FactoredEval, Float32Values, Grid, HalfValues, LogU8Values, TableEval, Unsupported, pca_table)

__all__ = ["Model", "Unsupported"]


def _floats(a):
    return mi.Float(np.ascontiguousarray(a, dtype=np.float32).reshape(-1))


class Model:
    def __init__(self, brdf):
        parts = brdf.parts()
        if parts is None:
            raise Unsupported(brdf.describe())
        kind = parts["kind"]
        self.kind = kind
        self.describe = brdf.describe()
        self._diff = {}  # differentiable arrays, by traverse name
        if kind == "analytic":
            self.analytic = AnalyticModel(parts["terms"], len(parts["params"]))
            self._diff["params"] = F64()(np.asarray(parts["params"], dtype=np.float64))
            sampler = brdf.sampler_parts()
            # A compact sampler's tables, or the lobe mixture's albedo table.
            self.sampler = CompactSampler(sampler) if sampler["kind"] == "compact" else None
            if self.sampler is None:
                self.albedo = F64()(np.asarray(sampler["albedo"], dtype=np.float64).reshape(-1))
            return
        self.grid = Grid(parts["grid"])
        sampler = brdf.sampler_parts()
        if sampler is None:
            raise Unsupported(f"{self.describe}: no sampler of its own")
        self.sampler = (CompactSampler if sampler["kind"] == "compact" else HalfVectorSampler)(sampler)
        if kind == "tabular":
            self._diff["values"] = _floats(parts["values"])
        elif kind == "compact":
            if parts["dtype"] == "f16":
                codes = np.ascontiguousarray(parts["codes"]).view(np.float16)
                self.codes = dr.float16_array_t(mi.Float)(codes)
                self._diff["half_scales"] = _floats(parts["half_scales"])
            else:
                self.codes = dr.uint8_array_t(mi.Float)(np.ascontiguousarray(parts["codes"]))
                self._diff["lut"] = _floats(parts["lut"])
        elif kind == "factored":
            self._diff["u"] = _floats(parts["u"])
            self._diff["v"] = _floats(parts["v"])
            if parts["colour"] == "shared":
                self._diff["colour_weights"] = _floats(parts["colour_weights"])
            self._factored = parts
        elif kind == "pca":
            self._pca = parts
            self.components = _floats(parts["components"])
            self.mean = _floats(parts["mean"])
            self.median = _floats(parts["median"])
            self.weights = _floats(parts["weights"])
            self._diff["coefficients"] = _floats(parts["coefficients"])
        else:
            raise Unsupported(f"kind {kind!r}")
        self.lookup = parts.get("lookup", "linear")
        self.parameters_changed()

    # --- parameters ---------------------------------------------------------------------------------
    def params(self) -> dict:
        """The differentiable arrays by name (the objects the evaluation reads: write them in place)."""
        return self._diff

    def parameters_changed(self) -> None:
        """Rebuilds what derives from the parameters: a PCA material's table."""
        if self.kind == "pca":
            self.values = pca_table(self._pca, self._diff["coefficients"], self.components, self.mean, self.median,
                                    self.weights)
            dr.eval(self.values)

    # --- brdf.h conventions on unit Float64 tuples --------------------------------------------------
    def _evaluator(self):
        d = self._diff
        k = self.kind
        if k == "tabular":
            return TableEval(self.grid, Float32Values(d["values"]), self.lookup)
        if k == "pca":
            return TableEval(self.grid, Float32Values(self.values), self.lookup)
        if k == "compact":
            values = HalfValues(self.codes, d["half_scales"]) if "half_scales" in d else LogU8Values(self.codes, d["lut"])
            return TableEval(self.grid, values, self.lookup)
        return FactoredEval(self.grid, self._factored, d["u"], d["v"], d.get("colour_weights"))

    def _lobe_params(self):
        p = self._diff["params"]
        return [dr.gather(F64(), p, u32(i)) for i in range(self.analytic.n_params)]

    def eval(self, wi, wo):
        """f_r(wi, wo), three Float64 arrays; 0 below the horizon."""
        above = (wi[2] > 0.0) & (wo[2] > 0.0)
        if self.kind == "analytic":
            f = self.analytic.eval(self._lobe_params(), wi, wo)
        else:
            f = self._evaluator()(wi, wo)
        return tuple(dr.select(above, c, 0.0) for c in f)

    def pdf(self, wo, wi):
        """Density of sample(wo, ·) at wi per unit solid angle; 0 below the horizon."""
        above = (wi[2] > 0.0) & (wo[2] > 0.0)
        if self.kind == "analytic" and self.sampler is None:
            p = self.analytic.pdf([dr.detach(x) for x in self._lobe_params()], self.albedo, wo, wi)
        else:
            p = self.sampler.pdf(wo, wi, above)
        return dr.select(above, p, 0.0)

    def sample(self, wo, u1, u2, active=True):
        """Brdf::sample's draw: (wi, pdf, ok); failed draws (not ok) have wi 0 and pdf 0."""
        can = active & (wo[2] > 0.0) & (u1 >= 0.0) & (u1 < 1.0) & (u2 >= 0.0) & (u2 < 1.0)
        if self.kind == "analytic" and self.sampler is None:
            wi, pdf, ok = self.analytic.sample([dr.detach(x) for x in self._lobe_params()], self.albedo, wo, u1, u2)
        else:
            wi, pdf, ok = self.sampler.sample(wo, u1, u2, can)
        ok = can & ok & (wi[2] > 0.0) & (pdf > 0.0) & (pdf < dr.inf)
        return tuple(dr.select(ok, c, 0.0) for c in wi), dr.select(ok, pdf, 0.0), ok
