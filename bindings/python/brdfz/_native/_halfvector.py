"""HalfVectorSampler (lib/src/sample/halfvector.cpp, piecewise2d.cpp) in Dr.Jit, on the C++ sampler's
own tables (Brdf.sampler_parts()), so draws and densities are the C++ ones: the same slices, CDFs,
guide tables and cell densities, the same float comparisons in the CDF searches, the same cell-
coordinate nudges. The C++ block kernel's two-step scans are its fast path to Piecewise2D's result;
here the search is Piecewise2D's loop itself (dr.while_loop), which gives that result for every draw.
Sines and cosines are Dr.Jit's (the C++ tables' results are within a few ulp of them), and so are
the square roots and divisions: draws agree to ~1e-15, pdfs to ~1e-12 relative."""
from __future__ import annotations

import numpy as np
import drjit as dr

from ._math import (BELOW_ONE, PI, F32, U32, u32, Azimuth, clamp, dot, f32, f64, gather32, gather_u32, half_turn_angle,
                    i32, next_down, next_up)


def _floats(a):
    return F32()(np.ascontiguousarray(a, dtype=np.float32))


def _uints(a):
    return U32()(np.ascontiguousarray(a, dtype=np.uint32))


class HalfVectorSampler:
    def __init__(self, parts: dict):
        self.share = float(parts["share"])
        theta_o = np.asarray(parts["theta_o"], dtype=np.float64)
        self.K, self.theta_max = len(theta_o), float(theta_o[-1])
        self.R, self.C = int(parts["rows"]), int(parts["cols"])
        self.marginal = _floats(parts["marginal"])
        self.conditional = _floats(parts["conditional"])
        self.density = _floats(parts["density"])
        self.marginal_guide = _uints(parts["marginal_guide"])
        self.conditional_guide = _uints(parts["conditional_guide"])

    def slice_span(self, theta_o):
        K = self.K
        scaled = theta_o / self.theta_max * (K - 1)
        pos = dr.select(scaled > 0.0, dr.select(scaled < K - 1.0, scaled, K - 1.0), 0.0)
        k0 = dr.minimum(i32(pos), K - 2)
        return k0, pos - f64(k0)

    def data_density(self, wo, sin_o, wi, active=True):
        """The data share's density of wi per unit solid angle (halfvector.cpp data_density)."""
        R, C = self.R, self.C
        s = Azimuth(wo, sin_o).to_local((wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]))
        rxy = dr.sqrt(s[0] * s[0] + s[1] * s[1])
        length = dr.sqrt(rxy * rxy + s[2] * s[2])
        y = dr.sqrt(half_turn_angle(rxy, s[2]) / (PI / 2.0))
        x = half_turn_angle(dr.abs(s[1]), s[0]) / PI
        inside = y < 1.0
        yc = dr.select(inside, y, 0.0)
        xc = dr.select(x < BELOW_ONE, x, BELOW_ONE)
        r = dr.minimum(i32(yc * R), R - 1)
        c = dr.minimum(i32(xc * C), C - 1)
        k0, t = self.slice_span(half_turn_angle(sin_o, wo[2]))
        cell = u32(r * C + c)
        base = u32(k0) * (R * C)
        p_xy = ((1.0 - t) * f64(gather32(self.density, base + cell, active))
                + t * f64(gather32(self.density, base + R * C + cell, active)))
        jac = 4.0 * ((sin_o * s[0] + wo[2] * s[2]) / length) * 2.0 * PI * PI * y * (rxy / length)
        p = p_xy / jac
        return dr.select(inside & (dr.abs(p) < dr.inf) & (p > 0.0), p, 0.0)

    def pdf(self, wo, wi, active=True):
        """Density of sample() at wi, for wo and wi above the horizon."""
        sin_o = dr.sqrt(wo[0] * wo[0] + wo[1] * wo[1])
        return self.share * wi[2] / PI + (1.0 - self.share) * self.data_density(wo, sin_o, wi, active)

    @staticmethod
    def find_interval(cdf, base, guide, guide_base, n: int, u, active):
        """piecewise2d.cpp find_interval on cdf[base ...] (n intervals) from its guide entry."""
        x = f32(u)
        j = dr.select(x > 0.0, dr.minimum(i32(f64(x) * n), n - 1), 0)
        i = i32(gather_u32(guide, guide_base + u32(j), active))

        def at(k):
            return gather32(cdf, base + u32(k), active)

        i = dr.while_loop((i,), lambda i: active & (i < n - 1) & (at(i + 1) <= x), lambda i: (i + 1,),
                          label="brdfz_cdf_scan")[0]
        i = dr.while_loop((i,), lambda i: active & (i > 0) & (at(i + 1) == at(i)), lambda i: (i - 1,),
                          label="brdfz_cdf_back")[0]
        i = dr.while_loop((i,), lambda i: active & (i < n - 1) & (at(i + 1) == at(i)), lambda i: (i + 1,),
                          label="brdfz_cdf_forward")[0]
        return i

    @staticmethod
    def cell_coord(i, n: int, f, active):
        """(i + f) / n, nudged so that floor(v·n) is i again (piecewise2d.cpp cell_coord)."""
        fi = f64(i)
        v = (fi + f) / n
        v = dr.while_loop((v,), lambda v: active & (v * n >= fi + 1.0), lambda v: (next_down(v),),
                          label="brdfz_cell_down")[0]
        v = dr.while_loop((v,), lambda v: active & (v * n < fi), lambda v: (next_up(v),), label="brdfz_cell_up")[0]
        return v

    def sample(self, wo, u1, u2, active):
        """For wo above the horizon and u in [0, 1)² (active lanes): (wi, pdf, ok), as
        HalfVectorSampler::draw; ok is Brdf::usable's test of the draw."""
        share, R, C = self.share, self.R, self.C
        sin_o = dr.sqrt(wo[0] * wo[0] + wo[1] * wo[1])
        cosine = u1 < share
        data = active & ~cosine

        # The cosine share: φ = 2πu2 folded as the C++ half-turn sine table reads it.
        e = u1 / share
        r = dr.sqrt(e)
        lower = u2 < 0.5
        ps, pc = dr.sincos(2.0 * PI * dr.select(lower, u2, 1.0 - u2))
        wi_c = (r * pc, r * dr.select(lower, ps, -ps), dr.sqrt(1.0 - e))
        pdf_c = share * wi_c[2] / PI + (1.0 - share) * self.data_density(wo, sin_o, wi_c, active & cosine)
        ok_c = wi_c[2] > 0.0

        # The data share: a slice by u1, then its piecewise-constant distribution over (x, y).
        v1 = (u1 - share) / (1.0 - share)
        k0, t = self.slice_span(half_turn_angle(sin_o, wo[2]))
        upper = ~(v1 < 1.0 - t)
        v1 = dr.select(upper, (v1 - (1.0 - t)) / t, v1 / (1.0 - t))
        sign = dr.select(lower, 1.0, -1.0)
        v2 = dr.select(lower, 2.0 * u2, 2.0 * u2 - 1.0)
        v1 = dr.select(v1 < BELOW_ONE, v1, BELOW_ONE)
        slice_ = dr.select(upper, k0 + 1, k0)

        row = self.find_interval(self.marginal, u32(slice_) * (R + 1), self.marginal_guide, u32(slice_) * R, R, v1,
                                 data)
        mb = u32(slice_) * (R + 1) + u32(row)
        m0, m1 = gather32(self.marginal, mb, data), gather32(self.marginal, mb + 1, data)
        fy = clamp((v1 - f64(m0)) / f64(m1 - m0), 0.0, 1.0)
        rs = u32(slice_) * R + u32(row)
        col = self.find_interval(self.conditional, rs * (C + 1), self.conditional_guide, rs * C, C, v2, data)
        cb = rs * (C + 1) + u32(col)
        c0, c1 = gather32(self.conditional, cb, data), gather32(self.conditional, cb + 1, data)
        fx = clamp((v2 - f64(c0)) / f64(c1 - c0), 0.0, 1.0)
        x = self.cell_coord(col, C, fx, data)
        y = self.cell_coord(row, R, fy, data)

        # halfvector.cpp finish: h at the cell point in wo's frame, wi its mirror, the pdf from wi (pdf()'s).
        th_s, th_c = dr.sincos(PI / 2.0 * y * y)
        ph_s, ph_c = dr.sincos(PI * x)
        sin_p = sign * ph_s
        h = Azimuth(wo, sin_o).to_world((th_s * ph_c, th_s * sin_p, th_c))
        cos_d = dot(wo, h)
        wi_d = (2.0 * cos_d * h[0] - wo[0], 2.0 * cos_d * h[1] - wo[1], 2.0 * cos_d * h[2] - wo[2])
        density = self.data_density(wo, sin_o, wi_d, data)
        ok_d = (wi_d[2] > 0.0) & (density > 0.0)
        pdf_d = share * wi_d[2] / PI + (1.0 - share) * density

        wi = tuple(dr.select(cosine, a, b) for a, b in zip(wi_c, wi_d))
        pdf = dr.select(cosine, pdf_c, pdf_d)
        ok = active & dr.select(cosine, ok_c, ok_d) & (wi[2] > 0.0) & (pdf > 0.0) & (pdf < dr.inf)
        return wi, pdf, ok
