"""The shaders against the C++ library on one material: eval and pdf on the same float32 direction
pairs, and the GPU sampler's draws against the same backend's eval and pdf."""

import numpy as np

from .layout import Layout

TOLERANCE = 1e-4  # relative, float32 against the library's double arithmetic rounded to float


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def pairs(n, seed=1):
    """n direction pairs above the horizon, as float32: half uniform over the hemisphere, half with wi
    near wo's mirror direction, where specular lobes and the sampler's narrow rows are."""
    rng = np.random.default_rng(seed)

    def hemisphere(m):
        z = rng.uniform(0.02, 1.0, m)
        phi = rng.uniform(0, 2 * np.pi, m)
        r = np.sqrt(1 - z * z)
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)

    half = n // 2
    wo = hemisphere(n)
    wi = hemisphere(n)
    h = _unit(np.array([0.0, 0.0, 1.0]) + rng.normal(0, 0.08, (n - half, 3)))
    mirror = 2 * np.sum(wo[half:] * h, -1, keepdims=True) * h - wo[half:]
    above = mirror[:, 2] > 0.02
    wi[half:][above] = mirror[above]
    return _unit(wi).astype(np.float32), _unit(wo).astype(np.float32)


# A factorisation's sum of float terms is known to some float ulps of its terms' magnitude per term:
# where they cancel to below this share of it, the value is judged on that scale (at 1e-4, 40 ulps of
# the magnitude, the rounding of a sum of tens of terms).
CANCELLATION = 0.05


NEGLIGIBLE = 2.0 ** -100  # 1/sr or 1/sr·(sr⁻¹): 8e-31, 2^26 times float's smallest normal number


def relative_error(gpu, ref, rounding=None):
    """Per row (a pair's channels, or one pdf): the largest |gpu − ref| over the row's largest |ref|
    (a colour's error relative to its brightness; values below NEGLIGIBLE taken as 0), or over
    CANCELLATION times its largest float rounding scale (Backend.rounding) where that is larger; 0
    where they are equal."""
    # Values below NEGLIGIBLE are zero in both: near float's underflow its arithmetic is not float32's to
    # give (GPUs flush subnormals; a sum of lobes each below the normal range), and a lobe's e^(n ln cos)
    # far from its peak is 1e-50 in double.
    tiny = NEGLIGIBLE
    gpu = np.asarray(gpu, np.float64).reshape(len(gpu), -1)
    ref = np.asarray(ref, np.float64).reshape(len(ref), -1)
    gpu = np.where(np.abs(gpu) < tiny, 0.0, gpu)
    ref = np.where(np.abs(ref) < tiny, 0.0, ref)
    diff = np.max(np.abs(gpu - ref), axis=1)
    scale = np.max(np.abs(ref), axis=1)
    if rounding is not None:
        scale = np.maximum(scale, CANCELLATION * np.max(np.abs(rounding), axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(diff == 0, 0.0, diff / scale)


def _jitter(v, rng, k):
    """k copies of unit directions with each component moved by up to 4 float32 ulps of 1: what float
    arithmetic on them (wi + wo first of all) rounds by, small components included."""
    eps = np.finfo(np.float32).eps
    return [v + rng.uniform(-4, 4, v.shape) * eps for _ in range(k)]


def excused(bad, ref_call, gpu_value, a, b, tol, rounding=None, seed=2):
    """Of the pairs `bad`, those whose GPU value is within `tol` of the library's at a direction pair
    within float rounding of theirs (_jitter): where the value is that sensitive to its directions (a
    nearest lookup's bin edge, a sampler's cell edge, a steep lobe), float arithmetic cannot do better.
    Such a pair is searched among random pairs in that box, then, where two of them give library values
    either side of the GPU's, by bisection on the segment between them (in the brightest channel): a
    steep but continuous value takes the GPU's somewhere there, a jump does not. Returns the mask over
    `bad`."""
    ok = np.zeros(len(bad), bool)
    if len(bad) == 0:
        return ok
    rng = np.random.default_rng(seed)
    gpu = np.asarray(gpu_value, np.float64)[bad].reshape(len(bad), -1)
    pa, pb = a[bad].astype(np.float64), b[bad].astype(np.float64)
    rb = None if rounding is None else rounding[bad]
    channel = None
    below = [None] * len(bad)
    above = [None] * len(bad)
    for ja, jb in zip(_jitter(pa, rng, 32), _jitter(pb, rng, 32)):
        ref = np.asarray(ref_call(ja, jb), np.float64).reshape(len(bad), -1)
        ok |= relative_error(gpu, ref, rb) <= tol
        if channel is None:
            channel = np.argmax(np.abs(ref), axis=1)
        rows = np.arange(len(bad))
        side = ref[rows, channel] - gpu[rows, channel]
        for i in np.flatnonzero(~ok):
            if side[i] < 0 and below[i] is None:
                below[i] = (ja[i], jb[i])
            elif side[i] > 0 and above[i] is None:
                above[i] = (ja[i], jb[i])
    todo = [i for i in np.flatnonzero(~ok) if below[i] is not None and above[i] is not None]
    if not todo:
        return ok
    lo_a = np.array([below[i][0] for i in todo]); lo_b = np.array([below[i][1] for i in todo])
    hi_a = np.array([above[i][0] for i in todo]); hi_b = np.array([above[i][1] for i in todo])
    g = gpu[todo]
    ch = channel[todo]
    r = None if rb is None else rb[todo]
    found = np.zeros(len(todo), bool)
    for _ in range(40):
        ma, mb = (lo_a + hi_a) / 2, (lo_b + hi_b) / 2
        ref = np.asarray(ref_call(ma, mb), np.float64).reshape(len(todo), -1)
        found |= relative_error(g, ref, r) <= tol
        lower = ref[np.arange(len(todo)), ch] < g[np.arange(len(todo)), ch]
        lo_a[lower], lo_b[lower] = ma[lower], mb[lower]
        hi_a[~lower], hi_b[~lower] = ma[~lower], mb[~lower]
    ok[np.array(todo)[found]] = True
    return ok


BACKENDS = ("wgpu", "gl", "webgl")


def backend(name="wgpu"):
    """A started backend by name (BACKENDS); BackendUnavailable when it cannot start."""
    if name == "wgpu":
        from .wgpu_backend import WgpuBackend

        return WgpuBackend()
    if name == "gl":
        from .gl_backend import GlBackend

        return GlBackend()
    if name == "webgl":
        from .webgl_backend import WebglBackend

        return WebglBackend()
    raise ValueError(f"unknown backend '{name}' (one of {', '.join(BACKENDS)})")


def check(material, gpu="wgpu", n=100_000, seed=1, tol=TOLERANCE):
    """The worst relative errors of the shaders on `gpu` (a backend or its name) against the library
    on `material` (a .brdfzrt path, or its Layout), and whether they are within `tol`. Raises
    BackendUnavailable when the backend cannot start."""
    import brdfz

    layout = material if isinstance(material, Layout) else Layout(material)
    gpu = (backend(gpu) if isinstance(gpu, str) else gpu).bind(layout)
    ref = brdfz.load(layout.path)
    wi, wo = pairs(n, seed)
    report = {"backend": f"{gpu.name} ({gpu.adapter})", "pairs": n}

    def measure(name, g, r, ref_call, a, b, rounding=None):
        err = relative_error(g, r, rounding)
        bad = np.flatnonzero(~(err <= tol))
        edge = excused(bad, ref_call, np.asarray(g).reshape(n, -1), a, b, tol, rounding)
        rest = err.copy()
        rest[bad[edge]] = 0.0
        report[name] = {"worst": float(np.max(rest)), "within_rounding": int(edge.sum()), "p99": float(np.quantile(err, 0.99))}
        return float(np.max(rest))

    f_gpu = gpu.eval(wi, wo)
    f_ref = ref.eval(wi.astype(np.float64), wo.astype(np.float64))
    worst = measure("eval", f_gpu, f_ref, ref.eval, wi, wo, gpu.rounding(wi, wo))
    p_gpu = gpu.pdf(wo, wi)
    p_ref = ref.pdf(wo.astype(np.float64), wi.astype(np.float64))
    worst = max(worst, measure("pdf", p_gpu, p_ref, ref.pdf, wo, wi))

    # The GPU sampler against the same backend: pdf(wo, wi) at its wi, and weight = f·cosθi/pdf.
    u = np.random.default_rng(seed + 1).random((n, 2), dtype=np.float32)
    s_wi, s_pdf, s_weight = gpu.sample(wo, u)
    drawn = s_pdf > 0
    p_back = gpu.pdf(wo[drawn], s_wi[drawn])
    f_back = gpu.eval(s_wi[drawn], wo[drawn])
    pdf_consistency = float(np.max(relative_error(s_pdf[drawn], p_back), initial=0.0))
    expected = f_back * (s_wi[drawn, 2] / s_pdf[drawn])[:, None]
    weight_consistency = float(np.max(relative_error(s_weight[drawn], expected), initial=0.0))
    # And the draws' pdfs against the library's at the same directions.
    d_wo, d_wi = wo[drawn], s_wi[drawn]
    pd_ref = ref.pdf(d_wo.astype(np.float64), d_wi.astype(np.float64))
    pd_err = relative_error(s_pdf[drawn], pd_ref)
    bad = np.flatnonzero(~(pd_err <= tol))
    edge = excused(bad, ref.pdf, s_pdf[drawn][:, None], d_wo, d_wi, tol)
    pd_err[bad[edge]] = 0.0
    report["sample"] = {"drawn": int(drawn.sum()), "pdf_vs_own_pdf": pdf_consistency,
                        "weight_vs_own_eval": weight_consistency, "pdf_vs_library": float(np.max(pd_err, initial=0.0)),
                        "within_rounding": int(edge.sum())}
    worst = max(worst, pdf_consistency, weight_consistency, float(np.max(pd_err, initial=0.0)))
    # The draws themselves: the same u gives the library's wi (to float rounding, but where rounding
    # puts u on the other side of a cell's edge), so the GPU draws from the library's density; and
    # draws that fail on the GPU but not in the library would be lost energy.
    ref_wi, ref_pdf, _ = ref.sample(wo.astype(np.float64), u.astype(np.float64))
    both = drawn & (ref_pdf > 0)
    report["sample"]["same_draw"] = float(np.mean(np.max(np.abs(s_wi[both] - ref_wi[both]), axis=1) < 1e-3))
    report["sample"]["failed"] = int((~drawn).sum())
    report["sample"]["failed_library"] = int((ref_pdf <= 0).sum())
    report["worst"] = worst
    report["ok"] = bool(worst <= tol)
    return report


def chi2(material, gpu="wgpu", theta_o=45.0, n=200_000, res=(32, 64), seed=3, against=None):
    """Pearson's χ² test of the GPU sampler's draws at wo (polar angle theta_o, in degrees, azimuth 0)
    against the same backend's pdf at wo (or at polar angle `against`, which a working sampler
    fails), integrated over res = (cosθ, φ) cells of equal solid angle by 8×8 midpoints each; cells
    expecting fewer than 5 draws pooled. Returns (statistic, degrees of freedom, p-value)."""
    from scipy.stats import chi2 as chi2_distribution

    layout = material if isinstance(material, Layout) else Layout(material)
    gpu = (backend(gpu) if isinstance(gpu, str) else gpu).bind(layout)
    t = np.radians(theta_o)
    wo1 = np.array([np.sin(t), 0.0, np.cos(t)], np.float32)
    u = np.random.default_rng(seed).random((n, 2), dtype=np.float32)
    wi, pdf, _ = gpu.sample(np.tile(wo1, (n, 1)), u)
    wi = wi[pdf > 0]
    nc, nphi = res
    sub = 8

    def cell_of(w):
        phi = np.mod(np.arctan2(w[:, 1], w[:, 0]), 2 * np.pi)
        return (np.minimum((w[:, 2] * nc).astype(int), nc - 1) * nphi +
                np.minimum((phi / (2 * np.pi) * nphi).astype(int), nphi - 1))

    observed = np.bincount(cell_of(wi), minlength=nc * nphi).astype(float)
    # The cells' midpoints: cosθ and φ on a (nc·sub) × (nphi·sub) grid, each point's solid angle equal.
    c = (np.arange(nc * sub) + 0.5) / (nc * sub)
    phi = (np.arange(nphi * sub) + 0.5) / (nphi * sub) * 2 * np.pi
    cc, pp = np.meshgrid(c, phi, indexing="ij")
    s = np.sqrt(1 - cc * cc)
    points = np.stack([s * np.cos(pp), s * np.sin(pp), cc], -1).reshape(-1, 3).astype(np.float32)
    t = np.radians(theta_o if against is None else against)
    wo_pdf = np.array([np.sin(t), 0.0, np.cos(t)], np.float32)
    density = gpu.pdf(np.tile(wo_pdf, (len(points), 1)), points).astype(float)
    mass = density.reshape(nc, sub, nphi, sub).sum(axis=(1, 3)) * (2 * np.pi / (nc * sub * nphi * sub))
    expected = mass.ravel() * n
    small = expected < 5
    obs = np.append(observed[~small], observed[small].sum())
    exp = np.append(expected[~small], expected[small].sum())
    keep = exp > 0
    statistic = float(np.sum((obs[keep] - exp[keep]) ** 2 / exp[keep]))
    dof = int(keep.sum()) - 1
    return statistic, dof, float(chi2_distribution.sf(statistic, dof))
