"""The native Mitsuba bridge (brdfz.mitsuba, brdfz/_native): tables, compact tables, factored, PCA
and analytic representations as Dr.Jit code.

- Through the BSDF's own eval / pdf / sample, at 10^5 pairs (float32 directions, as Mitsuba hands
  them over), the results equal brdfz's C++ Brdf.eval / pdf / sample to 1e-5 relative, every kind, on
  synthetic materials, a MERL table and an RGL-EPFL file's compressed forms (analytic and PCA
  materials with both settings of `incident`). Factored and PCA representations sum float32 terms in both implementations (the
  factors' blend; the components' combination), in different orders: there the bound is 1e-5
  relative plus 16 float32 roundings of those terms (Σ |term|, the size of the sum before it
  cancels), carried through the inverse transform.
- A sphere rendered through the native bridge (Mitsuba's default symbolic mode) matches the
  wavefront bridge to >= 60 dB PSNR.
- Gradients of a render reach every kind's arrays, and the inverse-rendering example's loss falls
  by >= 10x.
- Unsupported variants and kinds are clear errors; evaluation from several threads agrees; the
  registered plugin passes mitsuba.chi2.
"""
import gc
import json
import threading

import numpy as np
import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()
mi = pytest.importorskip("mitsuba")
import drjit as dr  # noqa: E402  (installed with mitsuba)
import brdfz.mitsuba  # noqa: E402  (needs mitsuba)
from brdfz.examples import inverse_render, mitsuba_sphere  # noqa: E402

N = 100_000
REL = 1e-5
EPS32 = 2.0 ** -24
MIN_PSNR_DB = 60.0

# Every lobe family, with parameters inside their bounds (model.h: one flat vector, term by term).
FAMILIES = {
    "lambert": {"rho_r": 0.3, "rho_g": 0.2, "rho_b": 0.1},
    "blinn_phong": {"ks_r": 0.2, "ks_g": 0.2, "ks_b": 0.3, "n": 40.0},
    "ward": {"ks_r": 0.2, "ks_g": 0.1, "ks_b": 0.1, "alpha": 0.3},
    "ggx": {"ks_r": 0.4, "ks_g": 0.3, "ks_b": 0.2, "alpha": 0.1, "f0": 0.04},
    "ggx_dielectric": {"ks_r": 0.3, "ks_g": 0.3, "ks_b": 0.3, "alpha": 0.3, "eta": 1.5},
    "ggx_conductor": {"ks_r": 0.5, "ks_g": 0.5, "ks_b": 0.5, "alpha": 0.05, "eta_r": 0.18, "eta_g": 0.42,
                      "eta_b": 1.37, "k_r": 3.42, "k_g": 2.35, "k_b": 1.77},
    "ggx_sep": {"ks_r": 0.2, "ks_g": 0.2, "ks_b": 0.2, "alpha": 0.5, "f0": 0.1},
    "ggx_dielectric_sep": {"ks_r": 0.2, "ks_g": 0.2, "ks_b": 0.2, "alpha": 0.02, "eta": 1.3},
    "ggx_conductor_sep": {"ks_r": 0.2, "ks_g": 0.3, "ks_b": 0.4, "alpha": 0.2, "eta_r": 1.0, "eta_g": 0.5,
                          "eta_b": 0.3, "k_r": 2.0, "k_g": 3.0, "k_b": 4.0},
    "beckmann": {"ks_r": 0.3, "ks_g": 0.2, "ks_b": 0.2, "alpha": 0.2, "f0": 0.05},
    "beckmann_dielectric": {"ks_r": 0.2, "ks_g": 0.2, "ks_b": 0.2, "alpha": 0.6, "eta": 2.0},
    "beckmann_conductor": {"ks_r": 0.2, "ks_g": 0.2, "ks_b": 0.2, "alpha": 0.05, "eta_r": 0.2, "eta_g": 0.9,
                           "eta_b": 1.1, "k_r": 3.9, "k_g": 2.4, "k_b": 2.2},
    "ggx_aniso": {"ks_r": 0.3, "ks_g": 0.3, "ks_b": 0.3, "alpha_x": 0.05, "alpha_y": 0.3, "f0": 0.04},
    "ashikhmin_shirley": {"rd_r": 0.3, "rd_g": 0.2, "rd_b": 0.1, "rs_r": 0.05, "rs_g": 0.05, "rs_b": 0.05,
                          "nu": 200.0, "nv": 20.0},
    "lafortune": {"rho_r": 0.2, "rho_g": 0.2, "rho_b": 0.2, "cxy": -0.9, "cz": 0.8, "n": 30.0},
}
GLOSSY = {"lambert.rho_r": 0.2, "lambert.rho_g": 0.3, "lambert.rho_b": 0.4, "ggx.ks_r": 1.0, "ggx.ks_g": 0.8,
          "ggx.ks_b": 0.6, "ggx.alpha": 0.15, "ggx.f0": 0.04}
SYNTHETIC_SPECS = [
    "tabular:res=16x16x32",
    "tabular:res=16x16x32,lookup=nearest",
    "tabular:res=16x16x32,dtype=f16",
    "tabular:res=12x12x24,dtype=u8log,dwarp=0.8",
    "tabular:res=16x12x24,dtype=f16,hwarp=2",
    "bivariate:res=16x16",
    "svd:rank=3,res=16x16x32",
    "svd:rank=2,space=cbrt,layout=hd_p,colour=shared,res=16x16x32,dtype=f16",
    "nmf:rank=2,space=linear,res=12x12x24",
    "tabular:res=16x16x32,sampler=fine",
    "svd:rank=3,res=16x16x32,sampler=fine",
]
RGL_SPECS = [
    "tabular:res=16x16x32",
    "tabular:res=16x16x16,dtype=u8log,dwarp=0.8",
    "tabular:res=16x16x16,dtype=f16,lookup=nearest",
    "svd:rank=4,space=cos,colour=shared,res=16x16x8,dwarp=0.9,dtype=f16",
    "svd:rank=4,space=cos,colour=shared,res=16x16x8,dtype=f16,hwarp=auto",
    "svd:rank=2,res=16x16x16",
    "analytic:lambert+ggx,starts=2",
]


SYMBOLIC = (dr.JitFlag.SymbolicLoops, dr.JitFlag.SymbolicCalls)


@pytest.fixture(scope="module")
def llvm():
    """llvm_ad_rgb in Mitsuba's default symbolic mode, which wavefront BSDFs built by earlier tests have
    switched off (and which `prb` needs): on once they are gone, restored afterwards."""
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception as e:  # no LLVM that Dr.Jit can use (scripts/setup-deps installs libllvm19)
        pytest.skip(f"Mitsuba's llvm_ad_rgb variant is unavailable: {e}")
    flags = {f: dr.flag(f) for f in SYMBOLIC}
    gc.collect()
    for f in SYMBOLIC:
        dr.set_flag(f, True)
    yield mi
    for f, v in flags.items():
        dr.set_flag(f, v)


def model_file(path, model, params):
    path.write_text(json.dumps({"format": "brdfz-analytic", "version": 1, "model": model, "parameters": params}))
    return path


@pytest.fixture(scope="module")
def glossy(tmp_path_factory):
    return brdfz.load(model_file(tmp_path_factory.mktemp("glossy") / "glossy.json", "lambert+ggx", GLOSSY))


@pytest.fixture(scope="module")
def every_lobe(tmp_path_factory):
    params = {f"{family}.{k}": v for family, p in FAMILIES.items() for k, v in p.items()}
    return brdfz.load(model_file(tmp_path_factory.mktemp("lobes") / "lobes.json", "+".join(FAMILIES), params))


@pytest.fixture(scope="module")
def pca_material(cli, tmp_path_factory):
    """k = 3 coefficients of a basis trained (brdfz pca-train) on five lambert+ggx materials."""
    d = tmp_path_factory.mktemp("pca")
    train = d / "train"
    train.mkdir()
    for i in range(5):
        p = dict(GLOSSY, **{"ggx.alpha": 0.1 + 0.1 * i, "lambert.rho_r": 0.2 + 0.1 * i, "lambert.rho_g": 0.5 - 0.05 * i})
        model_file(train / f"m{i}.json", "lambert+ggx", p)
    basis = d / "basis.brdfz"
    run(cli, "pca-train", train, "-o", basis, "--res", "8x8x16", "--k-max", "3")
    return brdfz.compress(brdfz.load(train / "m2.json"), f"pca:basis={basis},k=3")


def directions(rng, n, below=0.02):
    """Unit float32 rows, a share `below` the horizon."""
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) * np.where(rng.uniform(size=n) < below, -1.0, 1.0)
    return (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32)


def vec(a):
    return mi.Vector3f(np.ascontiguousarray(np.asarray(a, dtype=np.float32).T))


def rows(x):
    return np.array(x, dtype=np.float64).T


def float_bound(m, view, light):
    """|Δf| allowed between two evaluations of `m` at (wi = view, wo = light) that each sum a float32
    linear combination and then invert a transform (factored: the blend of the factors; PCA: the
    combination of the components, into a table): 16 float32 roundings of the sum's terms (Σ |term|,
    the size of the sum before it cancels), carried through the inverse transform. 0 for other kinds."""
    parts = m.parts()
    if parts is None or parts["kind"] not in ("factored", "pca"):
        return np.zeros((len(view), 3))
    from brdfz._native import Model
    from brdfz._native._math import directions as unit

    (a, _), (b, _) = unit(vec(view)), unit(vec(light))
    magnitude = Model(m)
    if parts["kind"] == "factored":
        # The same blend on |U|, |V|, |colour weights|, in linear space without a ceiling.
        magnitude._factored = dict(parts, space="linear", max_value=np.full(3, np.inf, np.float32))
        for name in ("u", "v", "colour_weights"):
            if name in magnitude._diff:
                magnitude._diff[name] = mi.Float(np.abs(np.asarray(parts[name], np.float32)).ravel())
        dy = 16 * EPS32 * rows(magnitude.eval(a, b))
        f = np.maximum(m.eval(view, light), 0.0)
        if parts["space"] == "log":
            return (1.0 + f) * dy * np.exp(dy)
        if parts["space"] == "cbrt":
            return 3 * (np.cbrt(f) + dy) ** 2 * dy
        return dy
    # PCA: per bin and channel f = (exp(y)·(m·w + ε) − ε)/w moves by (f + ε/w)·Δy; the lookup blends
    # the bins' bounds as it blends their values (the table's own invalid bins skipped alike).
    c = np.asarray(parts["coefficients"], np.float64)
    comps = np.asarray(parts["components"], np.float64)[: len(c)]
    mean = np.asarray(parts["mean"], np.float64)
    y = mean + c @ comps
    t = np.abs(mean) + np.abs(c) @ np.abs(comps)
    w = np.repeat(np.asarray(parts["weights"], np.float64), 3)
    eps = parts["epsilon"]
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.maximum((np.exp(y) * (parts["median"] * w + eps) - eps) / w, 0.0)
        dy = 16 * EPS32 * t
        per_bin = (f + eps / w) * dy * np.exp(dy)
    magnitude.values = mi.Float(np.where(np.isnan(np.array(magnitude.values)), np.nan, per_bin).astype(np.float32))
    return rows(magnitude.eval(a, b))


def within(ours, theirs, bound, what, m):
    err = np.abs(ours - theirs)
    ok = err <= REL * np.abs(theirs) + bound + 1e-35
    assert ok.all(), (f"{m.describe()}: {what}: {np.sum(~ok)} of {ok.size} beyond 1e-5 relative; worst "
                      f"{ours[~ok][:3]} against {theirs[~ok][:3]}")


def check_native(m, incident="camera", n=N, seed=1):
    """The native BSDF's eval, pdf and sample against the C++ Brdf at n pairs."""
    rng = np.random.default_rng(seed)
    bsdf = brdfz.mitsuba.bsdf(m, incident, native=True)
    assert "NativeBrdfzBSDF" in bsdf.to_string()
    view, light = directions(rng, n), directions(rng, n)
    u = rng.uniform(size=(n, 2)).astype(np.float32)
    ctx = mi.BSDFContext()
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = vec(view)
    lz = np.maximum(light[:, 2:3].astype(np.float64), 0.0)
    camera = incident == "camera"
    expected = (m.eval(view, light) if camera else m.eval(light, view)) * lz
    bound = (float_bound(m, view, light) if camera else float_bound(m, light, view)) * lz
    value, pdf = bsdf.eval_pdf(ctx, si, vec(light))
    within(rows(value), expected, bound, "eval", m)
    within(rows(bsdf.eval(ctx, si, vec(light))), expected, bound, "eval", m)
    expected_pdf = m.pdf(view, light)
    within(np.array(pdf, np.float64), expected_pdf, 0.0, "eval_pdf's pdf", m)
    within(np.array(bsdf.pdf(ctx, si, vec(light)), np.float64), expected_pdf, 0.0, "pdf", m)
    assert (expected_pdf[light[:, 2] <= 0] == 0).all()

    bs, weight = bsdf.sample(ctx, si, mi.Float(np.zeros(n, np.float32)), mi.Point2f(np.ascontiguousarray(u.T)))
    wi, spdf, sweight = m.sample(view, u.astype(np.float64))
    drawn = spdf > 0
    ours_pdf = np.array(bs.pdf, np.float64)
    assert np.array_equal(ours_pdf > 0, drawn), f"{m.describe()}: failed draws differ"
    assert np.abs(rows(bs.wo)[drawn] - wi[drawn]).max() <= REL
    within(ours_pdf, spdf, 0.0, "sample pdf", m)
    if camera:  # the weight of brdfz's wi at si.wi (mitsuba.py): that eval over the same pdf
        f = m.eval(view[drawn], wi[drawn]) * wi[drawn, 2:3] / spdf[drawn, None]
        fb = float_bound(m, view[drawn], wi[drawn]) * wi[drawn, 2:3] / spdf[drawn, None]
    else:
        f = sweight[drawn]
        fb = float_bound(m, wi[drawn], view[drawn]) * wi[drawn, 2:3] / spdf[drawn, None]
    within(rows(weight)[drawn], f, fb, "sample weight", m)
    assert (rows(weight)[~drawn] == 0).all()


def test_parts_are_read_only_views_of_the_representation(glossy):
    t = brdfz.compress(glossy, "tabular:res=8x8x16")
    parts = t.parts()
    assert parts["kind"] == "tabular" and parts["grid"]["n_phi_d"] == 16 and parts["lookup"] == "linear"
    assert np.array_equal(parts["values"], t.table.reshape(-1), equal_nan=True)
    with pytest.raises(ValueError):
        parts["values"][0] = 1.0
    sampler = t.sampler_parts()
    K, R, C = sampler["slices"], sampler["rows"], sampler["cols"]
    assert sampler["kind"] == "compact" and len(sampler["col_cdf"]) == K * R * C and len(sampler["row_cdf"]) == K * R
    assert len(sampler["s_edges"]) == R + 1 and len(sampler["edge_weight"]) == K * (R + 1)
    fine = brdfz.compress(glossy, "tabular:res=8x8x16,sampler=fine").sampler_parts()
    assert fine["kind"] == "halfvector" and len(fine["density"]) == len(fine["theta_o"]) * 64 * 64
    f = brdfz.compress(glossy, "svd:rank=2,colour=shared,res=8x8x16").parts()
    assert f["u"].shape == (8, 2) and f["v"].shape == (8 * 16, 2) and f["colour_weights"].shape == (3, 2)
    a = glossy.parts()
    assert a["terms"] == [("lambert", 0, "lambert"), ("ggx", 3, "ggx")] and list(a["params"]) == list(GLOSSY.values())
    assert glossy.sampler_parts()["albedo"].shape == (16, 2)


@pytest.mark.parametrize("spec", SYNTHETIC_SPECS)
def test_tables_and_factors_match_the_library(llvm, glossy, spec):
    check_native(brdfz.compress(glossy, spec))


def test_analytic_models_match_the_library(llvm, glossy, every_lobe):
    for incident in ("camera", "light"):
        check_native(glossy, incident)
        check_native(every_lobe, incident)


def test_pca_matches_the_library(llvm, pca_material):
    assert pca_material.parts()["kind"] == "pca"
    check_native(pca_material)
    check_native(pca_material, "light")


def test_rgl_representations_match_the_library(llvm, rgl_files):
    """Real data: an RGL-EPFL file compressed with small specs, every native kind."""
    source = brdfz.load(rgl_files[0])
    for spec in RGL_SPECS:
        check_native(brdfz.compress(source, spec))


def test_merl_table_matches_the_library(llvm, merl_tables):
    """A full 90x90x180 MERL table (from ../shared), both lookups: nearest picks MERL's bins."""
    for lookup in ("linear", "nearest"):
        check_native(brdfz.load(merl_tables[0], lookup=lookup))


def test_rgl_pca_matches_the_library(llvm, cli, rgl_files, tmp_path):
    train = tmp_path / "train"
    train.mkdir()
    for path in rgl_files[:4]:
        (train / path.name).symlink_to(path)
    basis = tmp_path / "basis.brdfz"
    run(cli, "pca-train", train, "-o", basis, "--res", "8x8x16", "--k-max", "3")
    check_native(brdfz.compress(brdfz.load(rgl_files[-1]), f"pca:basis={basis},k=3"))


def test_native_renders_as_the_wavefront_bridge(llvm, glossy, rgl_files):
    """Same scene, samples and seed: the two bridges differ by float rounding only."""
    materials = [glossy, brdfz.compress(glossy, "svd:rank=3,res=16x16x32"),
                 brdfz.compress(brdfz.load(rgl_files[0]), "tabular:res=16x16x32,dtype=u8log")]
    flags = {f: dr.flag(f) for f in SYMBOLIC}
    try:
        for m in materials:
            native = mitsuba_sphere.render(brdfz.mitsuba.bsdf(m, native=True), 32, 8)  # symbolic mode
            wavefront = mitsuba_sphere.render(brdfz.mitsuba.bsdf(m, native=False), 32, 8)
            # Back to symbolic mode only once no wavefront BSDF is left: a symbolic call traces every
            # live BSDF instance, and the wavefront one cannot be traced.
            gc.collect()
            for f, v in flags.items():
                dr.set_flag(f, v)
            assert native.max() > 0
            psnr = mitsuba_sphere.psnr(wavefront, native)
            assert psnr >= MIN_PSNR_DB, f"{m.describe()}: {psnr:.1f} dB"
    finally:
        gc.collect()
        for f, v in flags.items():
            dr.set_flag(f, v)


def test_gradients_reach_every_kind(llvm, glossy, pca_material):
    for m in [glossy, pca_material, brdfz.compress(glossy, "tabular:res=8x8x16"),
              brdfz.compress(glossy, "tabular:res=8x8x16,dtype=u8log"),
              brdfz.compress(glossy, "tabular:res=8x8x16,dtype=f16"),
              brdfz.compress(glossy, "svd:rank=2,colour=shared,res=8x8x16")]:
        sc = inverse_render.scene(brdfz.mitsuba.bsdf(m, native=True), 16, 4)
        params = mi.traverse(sc)
        keys = [k for k in params.keys() if k.startswith("sphere.bsdf.")]
        assert keys, m.describe()
        for k in keys:
            dr.enable_grad(params[k])
        params.update()
        dr.backward(dr.mean(mi.render(sc, params, seed=0), axis=None))
        for k in keys:
            g = np.array(dr.grad(params[k]))
            assert np.isfinite(g).all() and np.abs(g).max() > 0, f"{m.describe()}: no gradient at {k}"


def test_inverse_render_example_recovers(llvm):
    r = inverse_render.recover(inverse_render.builtin(), iterations=40, res=32, spp=8)
    assert r["losses"][-1] <= r["losses"][0] / 10, r["losses"]
    assert r["log_ratio_after"] < r["log_ratio_before"] / 3


def test_unsupported_variants_and_kinds_are_clear_errors(llvm, glossy, rgl_files):
    rgl = brdfz.load(rgl_files[0])
    assert rgl.parts() is None and rgl.sampler_parts() is None
    with pytest.raises(ValueError, match="no native port"):
        brdfz.mitsuba.bsdf(rgl, native=True)
    try:
        mi.set_variant("llvm_ad_spectral")
        with pytest.raises(ValueError, match="llvm_ad_spectral.*not supported.*RGB"):
            brdfz.mitsuba.bsdf(glossy)
        mi.set_variant("scalar_rgb")
        with pytest.raises(ValueError, match="JIT variant"):
            brdfz.mitsuba.bsdf(glossy, native=True)
    finally:
        mi.set_variant("llvm_ad_rgb")


def test_non_reciprocal_grids_run_natively(llvm, rgl_files):
    """Tables and factors over the full φd circle or folded by the mirror (what keeps a non-reciprocal
    RGL file's two sides of a pair) are ported: they match the library at 10^5 pairs, and exchanging wi
    and wo changes the native BSDF's value as it changes the file's."""
    source = brdfz.load(rgl_files[0])
    for spec in ("tabular:res=16x16x32,symmetry=none",
                 "svd:rank=4,space=cos,colour=shared,res=16x16x16,dwarp=0.9,fit=lsq,weight=solid,symmetry=none,dtype=f16",
                 "tabular:res=16x16x16,symmetry=bilateral,dtype=u8log",
                 "svd:rank=4,space=cos,colour=shared,res=16x16x8,dwarp=0.9,fit=lsq,weight=solid,symmetry=bilateral,dtype=f16"):
        m = brdfz.compress(source, spec)
        assert m.parts()["grid"]["symmetry"] == spec.split("symmetry=")[1].split(",")[0]
        check_native(m)
        bsdf = brdfz.mitsuba.bsdf(m, native=True)
        rng = np.random.default_rng(5)
        a, b = directions(rng, 4096, below=0.0), directions(rng, 4096, below=0.0)

        def native(view, light):
            si = dr.zeros(mi.SurfaceInteraction3f, len(view))
            si.wi = vec(view)
            return rows(bsdf.eval(mi.BSDFContext(), si, vec(light))) / light[:, 2:3]

        forward, backward = native(a, b), native(b, a)
        assert np.abs(forward - backward).max() > 0.01 * np.abs(forward).max(), spec  # not a folded table


def test_phi_h_stacks_take_the_wavefront_bridge(llvm, glossy):
    """A stack of φh slices has no native port: native=True is a clear error, and the default bridge
    evaluates it through the library."""
    m = brdfz.compress(glossy, "tabular:res=8x4x8,phih=2,symmetry=none")
    assert m.parts() is None
    with pytest.raises(ValueError, match="no native port"):
        brdfz.mitsuba.bsdf(m, native=True)
    flags = {f: dr.flag(f) for f in SYMBOLIC}
    try:
        bsdf = brdfz.mitsuba.bsdf(m)
        assert "NativeBrdfzBSDF" not in bsdf.to_string()
        rng = np.random.default_rng(5)
        view, light = directions(rng, 4096), directions(rng, 4096)
        si = dr.zeros(mi.SurfaceInteraction3f, len(view))
        si.wi = vec(view)
        value = rows(bsdf.eval(mi.BSDFContext(), si, vec(light)))
        expected = m.eval(view, light) * np.maximum(light[:, 2:3], 0.0)
        assert np.allclose(value, expected, rtol=1e-5, atol=1e-7)
        del bsdf
    finally:
        gc.collect()
        for f, v in flags.items():
            dr.set_flag(f, v)
