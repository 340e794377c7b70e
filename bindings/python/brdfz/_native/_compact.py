"""The compact sampler (lib/runtime/include/brdfz/runtime/kernels/compact_sampler.h) in Dr.Jit, on the
C++ sampler's own tables (Brdf.sampler_parts()): the same slices, fixed-point CDFs, row edges and
searches, so draws and densities are the C++ ones. Sines and cosines are Dr.Jit's (the kernel's
polynomial is within a few ulp of them): draws agree to ~1e-15, pdfs to ~1e-12 relative."""
from __future__ import annotations

import numpy as np
import drjit as dr

from ._math import PI, F32, U32, clamp, f64, gather32, gather_u32, half_turn_angle, i32, u32

ROW_UNITS = 4294967295.0
COL_UNITS = 65535.0


class CompactSampler:
    def __init__(self, parts: dict):
        self.share = float(parts["share"])
        self.K, self.R, self.C = int(parts["slices"]), int(parts["rows"]), int(parts["cols"])
        self.cos_theta_max = float(parts["cos_theta_max"])
        self.s_edges = F32()(np.ascontiguousarray(parts["s_edges"], dtype=np.float32))
        self.row_cdf = U32()(np.ascontiguousarray(parts["row_cdf"], dtype=np.uint32))
        self.col_cdf = U32()(np.ascontiguousarray(parts["col_cdf"], dtype=np.uint32))
        weights = np.ascontiguousarray(parts["edge_weight"], dtype=np.uint16).view(np.float16)
        self.edge_weight = F32()(weights.astype(np.float32))

    @staticmethod
    def frame(wo):
        """view_frame: wo's azimuth (c, s) and sinθo; the identity at the pole."""
        r = dr.sqrt(wo[0] * wo[0] + wo[1] * wo[1])
        pos = r > 0.0
        return dr.select(pos, wo[0] / r, 1.0), dr.select(pos, wo[1] / r, 0.0), dr.select(pos, r, 0.0)

    def slice_pair(self, cos_o):
        K = self.K
        scaled = (1.0 - cos_o) / (1.0 - self.cos_theta_max) * (K - 1)
        pos = dr.select(scaled > 0.0, dr.select(scaled < K - 1.0, scaled, K - 1.0), 0.0)
        k0 = dr.minimum(i32(pos), K - 2)
        return k0, pos - f64(k0)

    @staticmethod
    def valid_azimuth(s, sin_o, cos_o):
        """φmax: the azimuth up to which the half vector at s reflects wo above the horizon."""
        q = s * (1.0 - s)
        a = cos_o * (1.0 - 8.0 * q)
        b = sin_o * 4.0 * dr.sqrt(q) * (1.0 - 2.0 * s)
        x = dr.select(b > 0.0, -a / b, dr.select(a > 0.0, -2.0, 2.0))
        inside = half_turn_angle(dr.sqrt(dr.maximum(1.0 - x * x, 0.0)), x)
        return dr.select(~(x > -1.0), PI, dr.select(~(x < 1.0), 0.0, inside))

    @staticmethod
    def first_above(ends, base, n: int, x, active, floats=False):
        """The first i in [0, n) with x < ends[base + i] (n − 1 when none), in the kernel's fixed steps."""
        i = u32(0)
        while n > 1:
            half = n // 2
            index = base + i + u32(half - 1)
            v = f64(gather32(ends, index, active)) if floats else f64(gather_u32(ends, index, active))
            i = dr.select(v <= x, i + u32(half), i)
            n -= half
        return i

    @staticmethod
    def interval(ends, base, i, units, active):
        hi = f64(gather_u32(ends, base + i, active))
        lo = dr.select(i > 0, f64(gather_u32(ends, base + i - 1, active & (i > 0))), 0.0)
        return (hi - lo) / units

    def row_shape(self, k, r, active):
        """Slice k's edge weights around row r, (1, 1) where both are 0."""
        base = k * (self.R + 1) + r
        a = f64(gather32(self.edge_weight, base, active))
        b = f64(gather32(self.edge_weight, base + 1, active))
        some = a + b > 0.0
        return dr.select(some, a, 1.0), dr.select(some, b, 1.0)

    @staticmethod
    def shape_at(a, b, tau):
        return (a + (b - a) * tau) / (0.5 * (a + b))

    @staticmethod
    def shape_inverse(a, b, x):
        c = x * 0.5 * (a + b)
        root = a + dr.sqrt(dr.maximum(a * a + 2.0 * (b - a) * c, 0.0))
        return clamp(dr.select(root > 0.0, 2.0 * c / root, x), 0.0, 1.0)

    def data_density(self, wo, wi, active=True):
        R, C = self.R, self.C
        c, s_, sin_o = self.frame(wo)
        s = (wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2])
        lx, ly = c * s[0] + s_ * s[1], c * s[1] - s_ * s[0]
        rxy2 = lx * lx + ly * ly
        length = dr.sqrt(rxy2 + s[2] * s[2])
        sh = rxy2 / (2.0 * length * (length + s[2]))
        r = self.first_above(self.s_edges, u32(1), R, sh, active, floats=True)
        phi_max = self.valid_azimuth(sh, sin_o, wo[2])
        cpos = half_turn_angle(dr.abs(ly), lx) / phi_max * C
        col = dr.select(cpos > 0.0, dr.minimum(i32(cpos), C - 1), 0)
        col = u32(col)
        k0, t = self.slice_pair(wo[2])
        e0 = f64(gather32(self.s_edges, r, active))
        e1 = f64(gather32(self.s_edges, r + 1, active))
        tau = clamp((sh - e0) / (e1 - e0), 0.0, 1.0)
        p = f64(0.0)
        for j in (0, 1):
            k = u32(k0 + j)
            w = t if j else 1.0 - t
            row = k * R + r
            a, b = self.row_shape(k, r, active)
            p += w * self.interval(self.row_cdf, k * R, r, ROW_UNITS, active) * \
                self.interval(self.col_cdf, row * C, col, COL_UNITS, active) * self.shape_at(a, b, tau)
        omega = 4.0 * (e1 - e0) * phi_max / C
        wo_h = (wo[0] * s[0] + wo[1] * s[1] + wo[2] * s[2]) / length
        density = p / (omega * 4.0 * wo_h)
        return dr.select((density > 0.0) & (density < dr.inf), density, 0.0)

    def pdf(self, wo, wi, active=True):
        """Density of sample() at wi, for wo and wi above the horizon."""
        return self.share * wi[2] / PI + (1.0 - self.share) * self.data_density(wo, wi, active)

    def sample(self, wo, u1, u2, active):
        """For wo above the horizon and u in [0, 1)² (active lanes): (wi, pdf, ok), as compact_sample."""
        share, R, C = self.share, self.R, self.C
        lower = u2 < 0.5
        cosine = u1 < share
        data = active & ~cosine
        # The cosine share.
        e = u1 / share
        r = dr.sqrt(e)
        ps, pc = dr.sincos(2.0 * PI * dr.select(lower, u2, 1.0 - u2))
        wi_c = (r * pc, r * dr.select(lower, ps, -ps), dr.sqrt(1.0 - e))
        # The data share: a slice by u1, its row, then the column by u2.
        c, s_, sin_o = self.frame(wo)
        k0, t = self.slice_pair(wo[2])
        v1 = (u1 - share) / (1.0 - share)
        upper = ~(v1 < 1.0 - t)
        v1 = dr.select(upper, (v1 - (1.0 - t)) / t, v1 / (1.0 - t))
        k = u32(dr.select(upper, k0 + 1, k0))
        x1 = v1 * ROW_UNITS
        row = self.first_above(self.row_cdf, k * R, R, x1, data)
        hi1 = f64(gather_u32(self.row_cdf, k * R + row, data))
        lo1 = dr.select(row > 0, f64(gather_u32(self.row_cdf, k * R + row - 1, data & (row > 0))), 0.0)
        fr = clamp(dr.select(hi1 > lo1, (x1 - lo1) / (hi1 - lo1), 0.5), 0.0, 1.0)
        cbase = (k * R + row) * C
        x2 = dr.select(lower, 2.0 * u2, 2.0 * u2 - 1.0) * COL_UNITS
        col = self.first_above(self.col_cdf, cbase, C, x2, data)
        hi2 = f64(gather_u32(self.col_cdf, cbase + col, data))
        lo2 = dr.select(col > 0, f64(gather_u32(self.col_cdf, cbase + col - 1, data & (col > 0))), 0.0)
        fc = clamp(dr.select(hi2 > lo2, (x2 - lo2) / (hi2 - lo2), 0.5), 0.0, 1.0)
        s0 = f64(gather32(self.s_edges, row, data))
        a, b = self.row_shape(k, row, data)
        s = s0 + self.shape_inverse(a, b, fr) * (f64(gather32(self.s_edges, row + 1, data)) - s0)
        sin_h = 2.0 * dr.sqrt(s * (1.0 - s))
        cos_h = 1.0 - 2.0 * s
        p_s, p_c = dr.sincos((f64(col) + fc) / C * self.valid_azimuth(s, sin_o, wo[2]))
        hx, hy = sin_h * p_c, dr.select(lower, sin_h * p_s, -sin_h * p_s)
        h = (c * hx - s_ * hy, s_ * hx + c * hy, cos_h)
        d = 2.0 * (wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2])
        wi_d = (d * h[0] - wo[0], d * h[1] - wo[1], d * h[2] - wo[2])
        wi = tuple(dr.select(cosine, a, b) for a, b in zip(wi_c, wi_d))
        ok = active & (wi[2] > 0.0)
        pdf = self.pdf(wo, wi, ok)
        return wi, pdf, ok & (pdf > 0.0)
