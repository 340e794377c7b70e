"""Analytic models (the lobe families, brdfz/runtime/kernels/lobes/*.h) and their mixture sampler
(kernels/lobe_mixture.h) in Dr.Jit, in Float64 as the C++ double instantiation: every family's eval,
its sampler and density, the albedo-proportional mixture on the C++ mixture's own albedo table
(Brdf.sampler_parts()).

Parameters arrive as a list of Float64 values (width 1), so that gradients reach them. The
Beckmann sampler's slope inversions are the C++ Newton iterations (dr.while_loop), with
erfc(−x) = 1 + erf(x) (its relative error stays below 1e-9 for the u a float32 sampler gives)."""
from __future__ import annotations

import drjit as dr

from ._math import (PI, clamp, dot, f64, i32, normalize, reflect, select3)
from ._tables import Unsupported

TINY = 1e-12          # lobe.h kTiny
DBL_MIN = 2.2250738585072014e-308
INV_SQRT_PI = 0.56418958354775628695
SLOPE_RANGE = 8.0
BELOW_ONE = 1.0 - 2.0 ** -53


def log1p(x):
    """log(1 + x) without cancellation (Kahan's: the rounding of 1 + x divided out)."""
    y = 1.0 + x
    z = y - 1.0
    return dr.select(z == 0.0, x, dr.log(y) * (x / z))


def erfc(x):
    return 1.0 - dr.erf(x)


class Geometry:
    """lobe.h make_geometry: the pair, its half vector (ẑ when degenerate) and d = wi·h in [0, 1]."""

    def __init__(self, wi, wo):
        self.ix, self.iy, self.iz = wi
        self.ox, self.oy, self.oz = wo
        sx, sy, sz = wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]
        n2 = sx * sx + sy * sy + sz * sz
        degenerate = ~(n2 > DBL_MIN)
        inv = 1.0 / dr.sqrt(dr.select(degenerate, DBL_MIN, n2))
        self.hx = dr.select(degenerate, 0.0, sx * inv)
        self.hy = dr.select(degenerate, 0.0, sy * inv)
        self.hz = dr.select(degenerate, 1.0, sz * inv)
        d = self.ix * self.hx + self.iy * self.hy + self.iz * self.hz
        self.d = dr.select(d > 1.0, 1.0, dr.select(d > 0.0, d, 0.0))


# --- microfacet.h ---------------------------------------------------------------------------------

def ggx_d(cos_m, alpha):
    a2 = alpha * alpha
    k = cos_m * cos_m * (a2 - 1.0) + 1.0
    return a2 / (PI * k * k)


def ggx_visibility_correlated(ci, co, alpha):
    a2 = alpha * alpha
    li = dr.sqrt(ci * ci * (1.0 - a2) + a2)
    lo = dr.sqrt(co * co * (1.0 - a2) + a2)
    return 0.5 / (co * li + ci * lo + TINY)


def ggx_visibility_separable(ci, co, alpha):
    a2 = alpha * alpha
    li = dr.sqrt(ci * ci * (1.0 - a2) + a2)
    lo = dr.sqrt(co * co * (1.0 - a2) + a2)
    return 1.0 / ((ci + li) * (co + lo))


def beckmann_d(cos_m, alpha):
    c2 = dr.maximum(cos_m * cos_m, TINY)
    a2 = alpha * alpha
    return dr.exp(-((1.0 - c2) / c2) / a2) / (PI * a2 * (c2 * c2))


def beckmann_g1(cos_v, alpha):
    sin_v = dr.sqrt(dr.maximum(1.0 - cos_v * cos_v, TINY * TINY))
    a = (cos_v / sin_v) / alpha
    g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return dr.select(a < 1.6, g, 1.0)


def beckmann_visibility_separable(ci, co, alpha):
    return (beckmann_g1(ci, alpha) / dr.maximum(ci, TINY)) * (beckmann_g1(co, alpha) / dr.maximum(co, TINY)) * 0.25


def ggx_aniso_d(hx, hy, hz, ax, ay):
    x, y = hx / ax, hy / ay
    k = x * x + y * y + hz * hz
    return 1.0 / (PI * ax * ay * k * k)


def ggx_aniso_visibility(g, ax, ay):
    ax2, ay2 = ax * ax, ay * ay
    li = dr.sqrt(g.iz * g.iz + ax2 * (g.ix * g.ix) + ay2 * (g.iy * g.iy))
    lo = dr.sqrt(g.oz * g.oz + ax2 * (g.ox * g.ox) + ay2 * (g.oy * g.oy))
    return 0.5 / (g.oz * li + g.iz * lo + TINY)


def fresnel_schlick(cos_d, f0):
    m = 1.0 - cos_d
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


def fresnel_dielectric(cos_i, eta):
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = dr.sqrt(dr.maximum(1.0 - sin2_t, 0.0))  # the floor only where the select discards the value
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return dr.select(tir, 1.0, (rs * rs + rp * rp) / 2.0)


def fresnel_conductor(cos_i, eta, k):
    c2 = cos_i * cos_i
    s2 = 1.0 - c2
    s4 = s2 * s2
    t0 = eta * eta - k * k - s2
    a2b2 = dr.sqrt(dr.maximum(t0 * t0 + 4.0 * eta * eta * k * k, TINY * TINY))
    a = dr.sqrt(dr.maximum(0.5 * (a2b2 + t0), TINY))
    t1, t2 = a2b2 + c2, 2.0 * cos_i * a
    rs = (t1 - t2) / (t1 + t2)
    t3, t4 = a2b2 * c2 + s4, t2 * s2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rs + rp)


# --- families: eval(g, p) -> three values, no cosine ---------------------------------------------

def _lambert(g, p):
    return tuple(p[c] * (1.0 / PI) for c in range(3))


def _blinn_phong(g, p):
    n = p[3]
    lobe = (n + 2.0) * (0.125 / PI) * dr.exp(n * dr.log(dr.maximum(g.hz, TINY)))
    return tuple(p[c] * lobe for c in range(3))


def _ward(g, p):
    a2 = p[3] * p[3]
    c2 = dr.maximum(g.hz * g.hz, TINY)
    tan2 = (g.hx * g.hx + g.hy * g.hy) / c2
    d2 = dr.maximum(g.d * g.d, TINY)
    lobe = dr.exp(-tan2 / a2) / ((4.0 * PI) * a2 * (d2 * c2 * c2))
    return tuple(p[c] * lobe for c in range(3))


def _dv_ggx_correlated(g, alpha):
    return ggx_d(g.hz, alpha) * ggx_visibility_correlated(g.iz, g.oz, alpha)


def _dv_ggx_separable(g, alpha):
    return ggx_d(g.hz, alpha) * ggx_visibility_separable(g.iz, g.oz, alpha)


def _dv_beckmann(g, alpha):
    return beckmann_d(g.hz, alpha) * beckmann_visibility_separable(g.iz, g.oz, alpha)


def _schlick(cos_d, p):
    f = fresnel_schlick(cos_d, p[0])
    return (f, f, f)


def _dielectric(cos_d, p):
    f = fresnel_dielectric(cos_d, p[0])
    return (f, f, f)


def _conductor(cos_d, p):
    return tuple(fresnel_conductor(cos_d, p[c], p[3 + c]) for c in range(3))


def _microfacet(dv, fresnel):
    def ev(g, p):
        v = dv(g, p[3])
        f = fresnel(g.d, p[4:])
        return tuple(p[c] * f[c] * v for c in range(3))
    return ev


def _ggx_aniso(g, p):
    v = ggx_aniso_d(g.hx, g.hy, g.hz, p[3], p[4]) * ggx_aniso_visibility(g, p[3], p[4])
    f = fresnel_schlick(g.d, p[5])
    return tuple(p[c] * f * v for c in range(3))


def _ashikhmin_shirley(g, p):
    nu, nv = p[6], p[7]
    xy = dr.maximum(g.hx * g.hx + g.hy * g.hy, TINY)
    e = (nu * (g.hx * g.hx) + nv * (g.hy * g.hy)) / xy
    log_cos = dr.log(dr.maximum(g.hz, TINY))
    denom = dr.maximum(g.d, TINY) * dr.maximum(dr.maximum(g.iz, g.oz), TINY)
    spec = dr.sqrt((nu + 1.0) * (nv + 1.0)) * (0.125 / PI) * dr.exp(e * log_cos) / denom
    m = 1.0 - g.d
    schlick = m * m * m * m * m

    def fifth(x):
        return x * x * x * x * x

    diff_shape = (1.0 - fifth(1.0 - g.iz / 2.0)) * (1.0 - fifth(1.0 - g.oz / 2.0))
    out = []
    for c in range(3):
        rd, rs = p[c], p[3 + c]
        fresnel = rs + (1.0 - rs) * schlick
        out.append(spec * fresnel + (28.0 / 23.0 / PI) * rd * (1.0 - rs) * diff_shape)
    return tuple(out)


def _lafortune(g, p):
    n = p[5]
    base = p[3] * (g.ix * g.ox + g.iy * g.oy) + p[4] * (g.iz * g.oz)
    power = dr.exp(n * dr.log(dr.maximum(base, TINY)))
    lobe = dr.select(base > 0.0, (n + 2.0) * (0.5 / PI) * power, 0.0)
    return tuple(p[c] * lobe for c in range(3))


# --- samplers: sample(p, wo, u1, u2) -> a direction on the sphere; density(p, wo, w) over it --------

def cosine_hemisphere(u1, u2):
    r = dr.sqrt(u1)
    s, c = dr.sincos(2.0 * PI * u2)
    return (r * c, r * s, dr.sqrt(dr.maximum(0.0, 1.0 - u1)))


def around_z(c, u):
    s = dr.sqrt(dr.maximum(0.0, 1.0 - c * c))
    ps, pc = dr.sincos(2.0 * PI * u)
    return (s * pc, s * ps, c)


def half_of(wo, w):
    """The unit half vector of wo and w, and whether it is defined (w ≠ −wo)."""
    s = (wo[0] + w[0], wo[1] + w[1], wo[2] + w[2])
    n2 = dot(s, s)
    ok = n2 > 1e-30
    inv = dr.select(ok, 1.0 / dr.sqrt(n2), 0.0)
    return (s[0] * inv, s[1] * inv, s[2] * inv), ok


def reflect_about_drawn_half(wo, h):
    away = ~(dot(wo, h) > 0.0)
    return reflect(wo, (dr.select(away, -h[0], h[0]), dr.select(away, -h[1], h[1]), h[2]))


def reflected_density(wo, w, p_h):
    h, ok = half_of(wo, w)
    ok = ok & (h[2] > 0.0)
    folded = dr.select(dot(wo, (-h[0], -h[1], h[2])) > 0.0, 1.0, 2.0)
    return dr.select(ok, folded * p_h(h) / (4.0 * dot(wo, h)), 0.0)


class CosineSampler:
    @staticmethod
    def sample(p, wo, u1, u2):
        return cosine_hemisphere(u1, u2)

    @staticmethod
    def density(p, wo, w):
        return dr.select(w[2] > 0.0, w[2] / PI, 0.0)


def ggx_visible_sample(wo, ax, ay, u1, u2):
    v = normalize((ax * wo[0], ay * wo[1], wo[2]))
    z = (1.0 - u2) * (1.0 + v[2]) - v[2]
    c = around_z(z, u1)
    hs = (c[0] + v[0], c[1] + v[1], c[2] + v[2])
    return reflect(wo, normalize((ax * hs[0], ay * hs[1], hs[2])))


def ggx_visible_density(wo, w, ax, ay):
    h, ok = half_of(wo, w)
    l = dr.sqrt(wo[2] * wo[2] + ax * ax * wo[0] * wo[0] + ay * ay * wo[1] * wo[1])
    return dr.select(ok & (h[2] > 0.0), ggx_aniso_d(h[0], h[1], h[2], ax, ay) / (2.0 * (wo[2] + l)), 0.0)


class GgxAnisoSampler:
    AX, AY = 3, 4  # where the lobe's parameters hold αx and αy

    @classmethod
    def sample(cls, p, wo, u1, u2):
        return ggx_visible_sample(wo, p[cls.AX], p[cls.AY], u1, u2)

    @classmethod
    def density(cls, p, wo, w):
        return ggx_visible_density(wo, w, p[cls.AX], p[cls.AY])


class GgxSampler(GgxAnisoSampler):
    AY = 3  # one α for both axes


def invert_cdf(evaluate, target, lo, hi, x, label):
    """kernels/lobes/sampling.h invert_cdf: Newton steps inside a shrinking bracket, bisection when a step leaves it."""
    active = dr.full(dr.mask_t(x), True, dr.width(x))
    it = dr.zeros(dr.int32_array_t(x), dr.width(x))

    def body(x, lo, hi, it, active):
        c, d = evaluate(x)
        hit = c == target
        above = c > target
        hi = dr.select(above, x, hi)
        lo = dr.select(above, lo, x)
        nxt = x - (c - target) / d
        nxt = dr.select((nxt > lo) & (nxt < hi), nxt, 0.5 * (lo + hi))
        stop = (dr.abs(nxt - x) <= 1e-13 * dr.maximum(1.0, dr.abs(x))) | ~(hi - lo > 1e-14)
        return dr.select(hit, x, nxt), lo, hi, it + 1, active & ~hit & ~stop

    x, lo, hi, it, active = dr.while_loop((x, lo, hi, it, active), lambda x, lo, hi, it, active: active & (it < 100),
                                          body, label=label)
    return x


def inverse_erf_guess(u):
    a = 0.147
    l = dr.log(4.0 * u * (1.0 - u))
    t = 2.0 / (PI * a) + 0.5 * l
    return clamp(dr.copysign(dr.sqrt(dr.sqrt(t * t - l / a) - t), u - 0.5), -SLOPE_RANGE, SLOPE_RANGE)


def beckmann_visible_norm(wo, alpha):
    s = dr.sqrt(wo[0] * wo[0] + wo[1] * wo[1])
    a = wo[2] / (alpha * s)  # inf at the pole
    return 0.5 * wo[2] * erfc(-a) + alpha * s * dr.exp(-a * a) * (0.5 * INV_SQRT_PI)


class BeckmannSampler:
    @staticmethod
    def sample(p, wo, u1, u2):
        alpha = p[3]
        v = normalize((alpha * wo[0], alpha * wo[1], wo[2]))
        sin_v = dr.sqrt(v[0] * v[0] + v[1] * v[1])
        cos_v = v[2]
        hi = dr.select(sin_v > 0.0, dr.minimum(cos_v / sin_v, SLOPE_RANGE), SLOPE_RANGE)

        def m(x):
            g = dr.exp(-x * x)
            return 0.5 * cos_v * erfc(-x) + sin_v * g * (0.5 * INV_SQRT_PI), g * (cos_v - x * sin_v) * INV_SQRT_PI

        m_hi = m(hi)[0]
        t = sin_v * sin_v
        guess = (1.0 - t) * inverse_erf_guess(u1) - t * dr.sqrt(-dr.log(dr.maximum(u1, 1e-300)))
        x = invert_cdf(m, u1 * m_hi, f64(-SLOPE_RANGE), hi, clamp(guess, -SLOPE_RANGE, hi), "brdfz_beckmann_x")

        def gauss(y):
            return 0.5 * erfc(-y), dr.exp(-y * y) * INV_SQRT_PI

        y = invert_cdf(gauss, u2, f64(-SLOPE_RANGE) + 0.0 * u2, f64(SLOPE_RANGE) + 0.0 * u2, inverse_erf_guess(u2),
                       "brdfz_beckmann_y")
        cp = dr.select(sin_v > 0.0, v[0] / sin_v, 1.0)
        sp = dr.select(sin_v > 0.0, v[1] / sin_v, 0.0)
        h = normalize((-alpha * (cp * x - sp * y), -alpha * (sp * x + cp * y), 1.0 + 0.0 * x))
        return reflect(wo, h)

    @staticmethod
    def density(p, wo, w):
        h, ok = half_of(wo, w)
        return dr.select(ok & (h[2] > 0.0), beckmann_d(h[2], p[3]) / (4.0 * beckmann_visible_norm(wo, p[3])), 0.0)


class BlinnPhongSampler:
    @staticmethod
    def sample(p, wo, u1, u2):
        c = dr.exp(log1p(-u1) / (p[3] + 2.0))
        return reflect_about_drawn_half(wo, around_z(c, u2))

    @staticmethod
    def density(p, wo, w):
        n = p[3]
        return reflected_density(wo, w, lambda h: (n + 2.0) * (0.5 / PI) * dr.exp((n + 1.0) * dr.log(h[2])))


class WardSampler:
    @staticmethod
    def sample(p, wo, u1, u2):
        tan2 = -p[3] * p[3] * log1p(-u1)
        return reflect_about_drawn_half(wo, around_z(1.0 / dr.sqrt(1.0 + tan2), u2))

    @staticmethod
    def density(p, wo, w):
        alpha = p[3]
        return reflected_density(wo, w, lambda h: beckmann_d(h[2], alpha) * h[2])


def ashikhmin_shirley_specular_share(p):
    spec = 0.0
    diff = 0.0
    for c in range(3):
        spec = spec + p[3 + c] + (1.0 - p[3 + c]) / 21.0
        diff = diff + p[c] * (1.0 - p[3 + c])
    return spec / (spec + diff)


class AshikhminShirleySampler:
    @staticmethod
    def sample(p, wo, u1, u2):
        share = ashikhmin_shirley_specular_share(p)
        diffuse = ~(u1 < share)
        w_d = cosine_hemisphere(dr.minimum((u1 - share) / (1.0 - share), BELOW_ONE), u2)
        v = 4.0 * u1 / share
        quadrant = dr.minimum(i32(v), 3)
        phi0 = dr.atan(dr.sqrt((p[6] + 1.0) / (p[7] + 1.0)) * dr.tan(0.5 * PI * (v - f64(quadrant))))
        phi = dr.select(quadrant == 0, phi0, dr.select(quadrant == 1, PI - phi0,
                                                       dr.select(quadrant == 2, PI + phi0, 2.0 * PI - phi0)))
        sp, cp = dr.sincos(phi)
        e = p[6] * cp * cp + p[7] * sp * sp
        c = dr.exp(log1p(-u2) / (e + 1.0))
        s = dr.sqrt(dr.maximum(0.0, 1.0 - c * c))
        w_s = reflect_about_drawn_half(wo, (s * cp, s * sp, c))
        return select3(diffuse, w_d, w_s)

    @staticmethod
    def density(p, wo, w):
        share = ashikhmin_shirley_specular_share(p)
        nu, nv = p[6], p[7]

        def p_h(h):
            xy = dr.maximum(h[0] * h[0] + h[1] * h[1], TINY)
            e = (nu * h[0] * h[0] + nv * h[1] * h[1]) / xy
            return dr.sqrt((nu + 1.0) * (nv + 1.0)) * (0.5 / PI) * dr.exp(e * dr.log(h[2]))

        return share * reflected_density(wo, w, p_h) + (1.0 - share) * CosineSampler.density(p, wo, w)


def _duff_basis(n):
    sign = dr.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    c = n[0] * n[1] * a
    return (1.0 + sign * n[0] * n[0] * a, sign * c, -sign * n[0]), (c, sign + n[1] * n[1] * a, -n[1])


class LafortuneSampler:
    @staticmethod
    def axis(p, wo):
        a = (p[3] * wo[0], p[3] * wo[1], p[4] * wo[2])
        length = dr.sqrt(dot(a, a))
        ok = length > 1e-12
        inv = dr.select(ok, 1.0 / length, 0.0)
        return (a[0] * inv, a[1] * inv, a[2] * inv), ok

    @staticmethod
    def sample(p, wo, u1, u2):
        a, ok = LafortuneSampler.axis(p, wo)
        t, b = _duff_basis(a)
        v = around_z(dr.exp(log1p(-u1) / (p[5] + 1.0)), u2)
        lobe = tuple(v[0] * t[i] + v[1] * b[i] + v[2] * a[i] for i in range(3))
        return select3(ok, lobe, cosine_hemisphere(u1, u2))

    @staticmethod
    def density(p, wo, w):
        a, ok = LafortuneSampler.axis(p, wo)
        c = dot(w, a)
        lobe = dr.select(c > 0.0, (p[5] + 1.0) * (0.5 / PI) * dr.exp(p[5] * dr.log(dr.maximum(c, TINY))), 0.0)
        return dr.select(ok, lobe, CosineSampler.density(p, wo, w))


FAMILIES = {
    # name: (eval, sampler, parameter count)
    "lambert": (_lambert, CosineSampler, 3),
    "blinn_phong": (_blinn_phong, BlinnPhongSampler, 4),
    "ward": (_ward, WardSampler, 4),
    "ggx": (_microfacet(_dv_ggx_correlated, _schlick), GgxSampler, 5),
    "ggx_dielectric": (_microfacet(_dv_ggx_correlated, _dielectric), GgxSampler, 5),
    "ggx_conductor": (_microfacet(_dv_ggx_correlated, _conductor), GgxSampler, 10),
    "ggx_sep": (_microfacet(_dv_ggx_separable, _schlick), GgxSampler, 5),
    "ggx_dielectric_sep": (_microfacet(_dv_ggx_separable, _dielectric), GgxSampler, 5),
    "ggx_conductor_sep": (_microfacet(_dv_ggx_separable, _conductor), GgxSampler, 10),
    "beckmann": (_microfacet(_dv_beckmann, _schlick), BeckmannSampler, 5),
    "beckmann_dielectric": (_microfacet(_dv_beckmann, _dielectric), BeckmannSampler, 5),
    "beckmann_conductor": (_microfacet(_dv_beckmann, _conductor), BeckmannSampler, 10),
    "ggx_aniso": (_ggx_aniso, GgxAnisoSampler, 6),
    "ashikhmin_shirley": (_ashikhmin_shirley, AshikhminShirleySampler, 8),
    "lafortune": (_lafortune, LafortuneSampler, 6),
}

ALBEDO_NODES = 16  # LobeMixture::kAlbedoNodes


class AnalyticModel:
    """AnalyticBrdf: a sum of lobes (Brdf.parts()'s "terms") and its LobeMixture sampler."""

    def __init__(self, terms, n_params: int):
        for name, _, _ in terms:
            if name not in FAMILIES:
                raise Unsupported(f"lobe family {name!r}")
        self.terms = [(FAMILIES[name], int(offset)) for name, offset, _ in terms]
        self.n_params = n_params

    def eval(self, p, wi, wo):
        g = Geometry(wi, wo)
        out = [0.0, 0.0, 0.0]
        for (ev, _, size), offset in self.terms:
            v = ev(g, p[offset:offset + size])
            out = [out[c] + v[c] for c in range(3)]
        return tuple(out)

    def lobe_weights(self, albedo, wo):
        """LobeMixture::lobe_weights: the lobes' shares at wo, and whether the model is black there."""
        n = len(self.terms)
        pos = clamp(wo[2] * ALBEDO_NODES - 0.5, 0.0, ALBEDO_NODES - 1.0)
        k0 = dr.minimum(i32(pos), ALBEDO_NODES - 2)
        t = pos - f64(k0)
        U = dr.uint32_array_t(type(pos))
        F = type(pos)
        w = [(1.0 - t) * dr.gather(F, albedo, U(k0) * n + j) + t * dr.gather(F, albedo, U(k0 + 1) * n + j)
             for j in range(n)]
        total = w[0]
        for j in range(1, n):
            total = total + w[j]
        black = ~(total > 0.0)
        return [x / total for x in w], black

    def folded_density(self, sampler, p, wo, wi):
        return sampler.density(p, wo, wi) + sampler.density(p, wo, (wi[0], wi[1], -wi[2]))

    def pdf(self, p, albedo, wo, wi):
        w, black = self.lobe_weights(albedo, wo)
        total = 0.0
        for j, ((_, sampler, size), offset) in enumerate(self.terms):
            q = p[offset:offset + size]
            total = total + dr.select(w[j] > 0.0, w[j] * self.folded_density(sampler, q, wo, wi), 0.0)
        return dr.select(black, CosineSampler.density(None, wo, wi), total)

    def sample(self, p, albedo, wo, u1, u2):
        """LobeMixture::sample: (wi, pdf, ok)."""
        w, black = self.lobe_weights(albedo, wo)
        n = len(self.terms)
        # u1 picks the lobe j (the first whose share's end exceeds it), then back to one with a share.
        j = dr.zeros(dr.int32_array_t(u1), dr.width(u1))
        start = dr.zeros(type(u1), dr.width(u1))
        done = dr.zeros(dr.mask_t(u1), dr.width(u1))
        for k in range(n - 1):
            step = ~done & ~(u1 < start + w[k])
            start = dr.select(step, start + w[k], start)
            j = dr.select(step, k + 1, j)
            done = done | ~step
        chosen = dr.zeros(dr.int32_array_t(u1), dr.width(u1))
        for k in range(n):
            chosen = dr.select((w[k] > 0.0) & (k <= j), k, chosen)
        wj = w[0]
        for k in range(1, n):
            wj = dr.select(chosen == k, w[k], wj)
        v = clamp((u1 - start) / wj, 0.0, BELOW_ONE)
        wi = cosine_hemisphere(u1, u2)
        drawn = None
        for k, ((_, sampler, size), offset) in enumerate(self.terms):
            d = sampler.sample(p[offset:offset + size], wo, v, u2)
            drawn = d if drawn is None else select3(chosen == k, d, drawn)
        wi = select3(black, wi, (drawn[0], drawn[1], dr.abs(drawn[2])))
        pdf = self.pdf(p, albedo, wo, wi)
        ok = (wi[2] > 0.0) & dr.isfinite(pdf) & (pdf > 0.0)
        return wi, pdf, ok
