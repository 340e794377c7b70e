"""Rusinkiewicz-grid representations in Dr.Jit: the bin coordinates of a pair (table.h's axis maps),
nearest and multilinear lookups skipping invalid samples (lib/src/detail/table_lookup.h), float32,
float16 and u8log storage (compact_table.cpp), the factored reconstruction (factored_eval.cpp) and the
PCA reconstruction of a table (pca.cpp).

Each evaluator maps unit Float64 direction tuples (wi, wo), both above the horizon, to f_r as three
Float64 arrays. The coordinates come from the pair's half frame, normalised (coords.h's bin_coords),
with fast_math.h's polynomial arctangent for the angles: within ~1e-10 of C++'s, whose own fast
path is within 5e-8 bins of the exact one, so linear lookups agree to ~1e-9 relative and nearest
lookups pick the same bin except within ~1e-9 bins of an edge.

The φd axis spans [0, π) folded by reciprocity, [0, 2π) on a symmetry=none grid (Grid.full: the
folded angle plus π where d_y < 0) or [0, π] folded by the mirror on a bilateral one (Grid.mirror:
the angle of (d_x, |d_y|), and the lookup clamped at the mirror planes φd = 0 and π), as
table_lookup.h's phi_d_coord and phi_d_span.
"""
from __future__ import annotations

import math

import drjit as dr
import numpy as np

from ._math import (PI, F32, U32, u32, clamp0, dot, f32, f64, gather32, half_turn_angle, i32)

_MAX_INDEX = 2 ** 32  # Dr.Jit arrays are indexed with 32-bit integers


class Unsupported(Exception):
    """A representation the native bridge cannot express (the wavefront bridge takes it)."""


class Span:
    """Two neighbouring samples along an axis and the weight of the second (table_lookup.h Span)."""

    def __init__(self, i0, i1, t):
        self.i0, self.i1, self.t = i0, i1, t


def clamped_span(c, n: int) -> Span:
    c = clamp0(c, n - 1.0)
    i0 = i32(c)
    i1 = dr.select(i0 + 1 < n, i0 + 1, i0)
    return Span(i0, i1, c - f64(i0))


def periodic_span(c, n: int) -> Span:
    c = dr.select(c < 0.0, c + n, c)
    c = dr.select(c < n, c, 0.0)  # c == n after rounding, or NaN
    i0 = i32(c)
    return Span(i0, dr.select(i0 + 1 < n, i0 + 1, 0), c - f64(i0))


def bin_of(u, n: int):
    return i32(clamp0(u, n - 1.0))


class Grid:
    """A GridSpec (table.h) from Brdf.parts()'s "grid"."""

    def __init__(self, g: dict):
        self.nh, self.nd, self.np = int(g["n_theta_h"]), int(g["n_theta_d"]), int(g["n_phi_d"])
        self.offset = 0.5 if g["position"] == "centre" else 0.0
        self.warp = float(g["theta_d_warp"])
        self.h_warp = float(g.get("theta_h_warp", 0.0))
        if g["symmetry"] not in ("reciprocal", "none", "bilateral"):
            raise Unsupported(f"a grid with symmetry={g['symmetry']}")
        self.full = g["symmetry"] == "none"
        self.mirror = g["symmetry"] == "bilateral"
        self.per_radian = (0.5 if self.full else 1.0) / PI  # as phi_d_coord rounds it
        self.bins = self.nh * self.nd * self.np
        if 3 * self.bins >= _MAX_INDEX:
            raise Unsupported(f"grid of {self.bins} bins is too large for 32-bit gathers")

    def theta_d_coord(self, theta_d, cos_d):
        lin = theta_d * (2.0 / PI)
        if self.warp == 0.0:
            return lin * self.nd
        return ((1.0 - self.warp) * lin + self.warp * (1.0 - cos_d)) * self.nd

    def theta_h_coord(self, theta_h):
        if self.h_warp == 0.0:
            return dr.sqrt(theta_h * (2.0 / PI)) * self.nh
        s = self.h_warp
        return theta_h / (theta_h + s) * ((PI / 2.0 + s) / (PI / 2.0)) * self.nh

    def coords(self, wi, wo):
        """Continuous bin coordinates (uh, ud, up) of a pair above the horizon."""
        s = (wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2])
        n2 = dot(s, s)
        degenerate = ~(n2 > 1e-300)  # opposite grazing directions: h = ẑ (coords.h half_vector)
        inv = dr.select(degenerate, 0.0, 1.0 / dr.sqrt(n2))
        hx, hy = s[0] * inv, s[1] * inv
        hz = dr.select(degenerate, 1.0, s[2] * inv)
        r = dr.sqrt(hx * hx + hy * hy)
        pos = r > 0.0
        cp = dr.select(pos, hx / r, 1.0)
        sp = dr.select(pos, hy / r, 0.0)
        # The difference vector: wi in the half frame (t, b, h) of coords.h's half_frame.
        dx = wi[0] * (hz * cp) + wi[1] * (hz * sp) - wi[2] * r
        dy = -sp * wi[0] + cp * wi[1]
        dz = wi[0] * hx + wi[1] * hy + wi[2] * hz
        theta_h = half_turn_angle(r, hz)
        theta_d = half_turn_angle(dr.sqrt(dx * dx + dy * dy), dz)
        phi_d = half_turn_angle(dr.abs(dy) if self.mirror else dy, dx)  # folded into [0, π]
        if self.full:
            phi_d = phi_d + dr.select(dy < 0.0, PI, 0.0)
        return (self.theta_h_coord(theta_h), self.theta_d_coord(theta_d, dz), phi_d * self.per_radian * self.np)

    def spans(self, c):
        uh, ud, up = c
        o = self.offset
        phi = clamped_span if self.mirror else periodic_span
        return clamped_span(uh - o, self.nh), clamped_span(ud - o, self.nd), phi(up - o, self.np)

    def nearest(self, c):
        uh, ud, up = c
        return self.index(bin_of(uh, self.nh), bin_of(ud, self.nd), bin_of(up, self.np))

    def index(self, ih, id_, ip):
        """MERL's bin order, as an unsigned index."""
        return u32(ip) + u32(self.np) * (u32(id_) + u32(self.nd) * u32(ih))


# ---------------------------------------------------------------------------------------------------
# Value storage: load(bin) -> three Float32 arrays, NaN for an invalid channel.

class Float32Values:
    def __init__(self, values):
        self.values = values  # Float, bins·3, interleaved

    def load(self, b):
        i = 3 * b
        return gather32(self.values, i), gather32(self.values, i + 1), gather32(self.values, i + 2)


class HalfValues:
    """float16 codes times a power-of-two scale per channel; the invalid code 0x7E00 is a NaN half."""

    def __init__(self, codes, scales):
        self.codes = codes    # Float16, bins·3
        self.scales = scales  # Float, 3

    def load(self, b):
        F16 = dr.float16_array_t(F32())
        i = 3 * b
        return tuple(f32(dr.gather(F16, self.codes, i + c)) * dr.gather(F32(), self.scales, u32(c))
                     for c in range(3))


class LogU8Values:
    """u8log codes through each channel's 256-entry table (code 255: NaN)."""

    def __init__(self, codes, lut):
        self.codes = codes  # UInt8, bins·3
        self.lut = lut      # Float, 3·256

    def load(self, b):
        U8 = dr.uint8_array_t(F32())
        i = 3 * b
        return tuple(gather32(self.lut, u32(dr.gather(U8, self.codes, i + c)) + 256 * c) for c in range(3))


def read_nearest(values, b):
    return tuple(dr.select(dr.isnan(v), 0.0, f64(v)) for v in values.load(b))


def read_linear(grid: Grid, values, spans):
    """The blend of the 8 corners, invalid samples skipped (table_lookup.h read_linear)."""
    h, d, p = spans
    total = [0.0, 0.0, 0.0]
    weight = [0.0, 0.0, 0.0]
    for a in (0, 1):
        ih = h.i1 if a else h.i0
        wa = h.t if a else 1.0 - h.t
        for b in (0, 1):
            id_ = d.i1 if b else d.i0
            wb = wa * (d.t if b else 1.0 - d.t)
            row = grid.index(ih, id_, 0)
            for q in (0, 1):
                w = wb * (p.t if q else 1.0 - p.t)
                x = values.load(row + u32(p.i1 if q else p.i0))
                for c in range(3):
                    ok = ~dr.isnan(x[c])
                    total[c] = total[c] + dr.select(ok, w * f64(x[c]), 0.0)
                    weight[c] = weight[c] + dr.select(ok, w, 0.0)
    return tuple(dr.select(weight[c] > 0.0, total[c] / weight[c], 0.0) for c in range(3))


class TableEval:
    """TabularBrdf / CompactTableBrdf / PcaBrdf evaluation: a grid, a storage policy, a lookup."""

    def __init__(self, grid: Grid, values, lookup: str):
        self.grid, self.values, self.linear = grid, values, lookup == "linear"

    def __call__(self, wi, wo):
        c = self.grid.coords(wi, wo)
        if self.linear:
            return read_linear(self.grid, self.values, self.grid.spans(c))
        return read_nearest(self.values, self.grid.nearest(c))


# ---------------------------------------------------------------------------------------------------
# Factored (factored.h): f = T⁻¹(min(Σ_j mix_cj·Ũ_j·Ṽ_j, ceiling_c)), the factors interpolated linearly.

def to_space(space: str, f: float) -> float:
    if space == "log":
        return math.log1p(f)
    if space == "cbrt":
        return f ** (1.0 / 3.0) if f > 0 else 0.0
    return f


class FactoredEval:
    def __init__(self, grid: Grid, parts: dict, u, v, colour_weights):
        self.grid = grid
        self.space = parts["space"]
        self.hxdp = parts["layout"] == "h_dp"
        self.shared = parts["colour"] == "shared"
        self.rank = int(parts["rank"])
        self.m = self.rank if self.shared else 3 * self.rank
        self.u, self.v, self.colour_weights = u, v, colour_weights  # Float arrays, row-major
        # The ceilings in the transform space, rounded to float as the float blend is clamped (factored.cpp).
        top = [min(float(x), 3.4028234663852886e38) for x in parts["max_value"]]
        self.ceiling = [float(np.float32(to_space(self.space, x))) for x in top]

    def corners(self, wi, wo):
        """Factor rows and columns to blend, and their float weights (factored_eval.cpp set_corners)."""
        g = self.grid
        h, d, p = g.spans(g.coords(wi, wo))

        def pairs(a, b, inner):
            idx = [u32(a.i0) * inner + u32(b.i0), u32(a.i0) * inner + u32(b.i1),
                   u32(a.i1) * inner + u32(b.i0), u32(a.i1) * inner + u32(b.i1)]
            w = [f32((1.0 - a.t) * (1.0 - b.t)), f32((1.0 - a.t) * b.t), f32(a.t * (1.0 - b.t)), f32(a.t * b.t)]
            return idx, w

        if self.hxdp:
            rows, rw = [u32(h.i0), u32(h.i1)], [f32(1.0 - h.t), f32(h.t)]
            cols, cw = pairs(d, p, g.np)
        else:
            rows, rw = pairs(h, d, g.nd)
            cols, cw = [u32(p.i0), u32(p.i1)], [f32(1.0 - p.t), f32(p.t)]
        return rows, rw, cols, cw

    def __call__(self, wi, wo):
        rows, rw, cols, cw = self.corners(wi, wo)
        m = self.m
        products = []
        for j in range(m):
            a = rw[0] * gather32(self.u, rows[0] * m + j)
            for r in range(1, len(rows)):
                a = a + rw[r] * gather32(self.u, rows[r] * m + j)
            b = cw[0] * gather32(self.v, cols[0] * m + j)
            for c in range(1, len(cols)):
                b = b + cw[c] * gather32(self.v, cols[c] * m + j)
            products.append(a * b)
        out = []
        for ch in range(3):
            if self.shared:
                y = 0.0
                for j in range(self.rank):
                    y = y + dr.gather(F32(), self.colour_weights, u32(ch * self.rank + j)) * products[j]
            else:
                y = products[ch * self.rank]
                for j in range(1, self.rank):
                    y = y + products[ch * self.rank + j]
            y = dr.minimum(y, self.ceiling[ch])
            out.append(self.from_space(y))
        return tuple(out)

    def from_space(self, y):
        """The value of a float reconstruction, negatives clamped to 0 (factored_impl.h from_space)."""
        q = dr.maximum(f64(y), 0.0)
        if self.space == "log":
            return dr.exp(q) - 1.0  # in double: exp − 1 keeps the float reconstruction's digits
        if self.space == "cbrt":
            return q * q * q
        return q


# ---------------------------------------------------------------------------------------------------
# PCA (pca.h): the table of a coefficient vector, mean + Σ c_j·component_j mapped back per bin.

def pca_table(parts: dict, coefficients, components, mean, median, weights):
    """bins·3 Float values: (exp(y)·(m·w + ε) − ε)/w clamped at 0; a bin whose median is NaN
    (dropped) or whose value is not a finite float is invalid (NaN), as PcaBasis::reconstruct."""
    dims = dr.width(mean)
    e = dr.arange(U32(), dims)
    y = mean
    for j in range(dr.width(coefficients)):
        y = y + dr.gather(F32(), coefficients, u32(j)) * dr.gather(F32(), components, u32(j * dims) + e)
    bin_ = e // 3
    w = f64(dr.gather(F32(), weights, bin_))
    m = f64(median)
    eps = float(parts["epsilon"])
    v = (dr.exp(f64(y)) * (m * w + eps) - eps) / w
    finite = dr.isfinite(f32(v))
    dr.eval(finite)
    b3 = 3 * bin_
    ok = (dr.gather(type(finite), finite, b3) & dr.gather(type(finite), finite, b3 + 1)
          & dr.gather(type(finite), finite, b3 + 2) & ~dr.isnan(dr.gather(F32(), median, b3)))
    return dr.select(ok, f32(dr.maximum(v, 0.0)), math.nan)
