"""Dr.Jit versions of brdfz's small numeric helpers (lib/src/detail/fast_math.h, frame.h, azimuth.h),
operation for operation, on the current Mitsuba variant's arrays. Geometry runs in Float64 as in C++;
types are looked up from the variant at call time, so one module serves llvm and cuda variants."""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

PI = math.pi
BELOW_ONE = 1.0 - 2.0 ** -53  # the largest double below 1 (0x1.fffffffffffffp-1)


# The variant's array types. Called while tracing, so the variant in force is the one rendering.
def F32():
    return mi.Float


def F64():
    return dr.float64_array_t(mi.Float)


def I32():
    return dr.int32_array_t(mi.Float)


def U32():
    return dr.uint32_array_t(mi.Float)


def U64():
    return dr.uint64_array_t(mi.Float)


def f64(x):
    return F64()(x)


def f32(x):
    return F32()(x)


def u32(x):
    return U32()(x)


def i32(x):
    """Truncation towards zero, as static_cast<int>."""
    return I32()(x)


def gather32(source, index, active=True):
    return dr.gather(F32(), source, index, active)


def gather_u32(source, index, active=True):
    return dr.gather(U32(), source, index, active)


# std::min / std::max semantics with NaN (a NaN first argument is returned, a NaN second is not).
def std_min(a, b):
    return dr.select(b < a, b, a)


def std_max(a, b):
    return dr.select(a < b, b, a)


def clamp(x, lo, hi):
    """std::clamp(x, lo, hi): comparisons, NaN passes through."""
    return dr.select(x < lo, lo, dr.select(hi < x, hi, x))


def clamp0(u, hi):
    """table_lookup.h clamp0: [0, hi], NaN to 0."""
    return dr.select(u > 0.0, dr.select(u < hi, u, hi), 0.0)


_ATAN = (0.99999999994136979, -0.33333331572392677, 0.19999912082711904, -0.1428398114194897,
         0.1109324385371387, -0.089802498131937941, 0.072457466235865964, -0.054279596397618646,
         0.034210157407729216, -0.016112066961960693, 0.0048510884142120014, -0.00068481937721016906)


def atan01(t):
    """fast_math.h atan01: atan(t) for t in [0, 1], Estrin's scheme, |relative error| < 6e-11."""
    c = _ATAN
    x = t * t
    x2 = x * x
    x4 = x2 * x2
    x8 = x4 * x4
    p01, p23, p45, p67 = c[0] + c[1] * x, c[2] + c[3] * x, c[4] + c[5] * x, c[6] + c[7] * x
    p89, pab = c[8] + c[9] * x, c[10] + c[11] * x
    q0, q1, q2 = p01 + p23 * x2, p45 + p67 * x2, p89 + pab * x2
    return t * ((q0 + q1 * x4) + q2 * x8)


def half_turn_angle(y, x):
    """fast_math.h fast_half_turn_angle: the angle of (x, y) folded into [0, π]."""
    ax, ay = dr.abs(x), dr.abs(y)
    a = atan01(std_min(ax, ay) / std_max(ax, ay))
    steep = dr.select(ay > ax, 1.0, 0.0)
    left = dr.select((x < 0.0) != (y < 0.0), 1.0, 0.0)
    b = a + steep * (PI / 2 - 2.0 * a)
    return b + left * (PI - 2.0 * b)


# 3-vectors as tuples of arrays (x, y, z).
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def select3(m, a, b):
    return (dr.select(m, a[0], b[0]), dr.select(m, a[1], b[1]), dr.select(m, a[2], b[2]))


def length(a):
    return dr.sqrt(dot(a, a))


def normalize(a):
    return scale(1.0 / length(a), a)


def reflect(wo, h):
    return sub(scale(2.0 * dot(wo, h), h), wo)


def directions(v, active=True):
    """A Mitsuba Vector3f as a unit Float64 3-tuple, normalised in double as brdfz's Python binding
    normalises rows, and whether it is usable (finite, non-zero, active): unusable lanes become
    (0, 0, -1), below the horizon, where every brdfz function returns 0."""
    x, y, z = f64(v[0]), f64(v[1]), f64(v[2])
    n = dr.sqrt(x * x + y * y + z * z)
    ok = active & dr.isfinite(n) & (n > 0.0)
    inv = dr.select(ok, 1.0 / n, 0.0)
    return (dr.select(ok, x * inv, 0.0), dr.select(ok, y * inv, 0.0), dr.select(ok, z * inv, -1.0)), ok


class Azimuth:
    """azimuth.h: w's azimuth as a rotation (c, s), the identity at the pole."""

    def __init__(self, w, r=None):
        if r is None:
            r = dr.sqrt(w[0] * w[0] + w[1] * w[1])
        pos = r > 0.0
        self.c = dr.select(pos, w[0] / r, 1.0)
        self.s = dr.select(pos, w[1] / r, 0.0)

    def to_local(self, v):
        return (self.c * v[0] + self.s * v[1], -self.s * v[0] + self.c * v[1], v[2])

    def to_world(self, v):
        return (self.c * v[0] - self.s * v[1], self.s * v[0] + self.c * v[1], v[2])


def next_down(v):
    """std::nextafter(v, 0) for v > 0 (doubles)."""
    U = U64()
    return dr.reinterpret_array(F64(), dr.reinterpret_array(U, v) - U(1))


def next_up(v):
    """std::nextafter(v, 1) for 0 <= v < 1 (doubles)."""
    U = U64()
    return dr.reinterpret_array(F64(), dr.reinterpret_array(U, v) + U(1))
