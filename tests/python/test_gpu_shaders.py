"""The GPU shaders (bindings/gpu/shaders, through brdfz.gpu) against the C++ library on every backend
that starts here (wgpu: Mesa's lavapipe, Vulkan; gl: Mesa's llvmpipe, OpenGL 4.5 through EGL, where
there is no GPU; webgl: WebGL2 fragment shaders in headless Chromium, SwiftShader): eval and pdf within 1e-4 of the library on float32 direction pairs, every GPU draw's
pdf and weight equal to the same backend's pdf and eval, and the library's draw for the same u, on
compact representations of a real RGL file of every kind the shaders evaluate (tables of each dtype
and symmetry, svd and nmf factors, lobe mixtures, φh stacks) with their samplers."""

import pytest

from conftest import SHARED, exported_layouts, import_brdfz

RGL = SHARED / "data" / "rgl" / "satin_purple_rgb.bsdf"
PAIRS = 20_000

# One per kind and variant the shaders read: value dtypes, φd axes, lookups, factor layouts, spaces,
# shared and separate colour (ranks 3-4 take the grouped sums), float16 and float32 factors.
SPECS = {
    "table_f16": "tabular:res=45x45x90,dtype=f16",
    "table_u8log_none": "tabular:res=45x45x90,dtype=u8log,symmetry=none",
    "table_f32_bilateral_nearest": "tabular:res=45x45x90,symmetry=bilateral,lookup=nearest",
    "svd_cos_shared": "svd:rank=10,space=cos,colour=shared,res=25x20x14,dwarp=0.9,fit=lsq,symmetry=bilateral,dtype=f16",
    "svd_log_hd_p": "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16",
    "svd_log_separate": "svd:rank=3,space=log,res=20x14x32",
    "nmf": "nmf:rank=4,res=32x32x32",
    # θh axes warped by the material's peak.
    "table_f16_hwarp": "tabular:res=45x45x90,dtype=f16,symmetry=bilateral,hwarp=auto",
    "svd_cos_hwarp": "svd:rank=6,space=cos,colour=shared,res=32x22x13,dwarp=0.9,symmetry=bilateral,dtype=f16,hwarp=auto",
    # φh stacks of tables and of factorisations, on the full and the mirror-folded φh range.
    "phi_h_tables": "tabular:res=32x16x32,phih=8,symmetry=none",
    "phi_h_svd_bilateral": "svd:rank=4,space=log,res=16x10x16,phih=4,symmetry=bilateral",
    # Lobe mixtures of every lobe family the shaders have.
    "lobes": "analytic:lambert+ggx,starts=2",
    "lobes_conductor_sep": "analytic:lambert+ggx_conductor_sep,starts=2",
    "lobes_dielectric_aniso": "analytic:ggx_dielectric+ggx_aniso,starts=2",
    "lobes_phong_ward": "analytic:blinn_phong+ward,starts=2",
    "lobes_lafortune": "analytic:lambert+lafortune2,starts=2",
    "lobes_beckmann": "analytic:lambert+beckmann_dielectric,starts=2",
    "lobes_ashikhmin_shirley": "analytic:ashikhmin_shirley,starts=2",
}
# Models drawn by their lobes' own samplers (sampler=lobes) rather than the compact sampler.
LOBE_SAMPLED = {
    "lobes_sampled_phong": "analytic:lambert+blinn_phong,starts=2,sampler=lobes",
    "lobes_sampled_ward": "analytic:lambert+ward,starts=2,sampler=lobes",
    "lobes_sampled_lafortune": "analytic:lafortune3,starts=2,sampler=lobes",
    "lobes_sampled_beckmann": "analytic:lambert+beckmann,starts=2,sampler=lobes",
    "lobes_sampled_ashikhmin_shirley": "analytic:ashikhmin_shirley,starts=2,sampler=lobes",
}


@pytest.fixture(scope="module", params=["wgpu", "gl", "webgl"])
def gpu(request):
    import_brdfz()
    if not RGL.exists():
        pytest.skip(f"../shared is missing ({RGL})")
    from brdfz import gpu as brdfz_gpu

    try:
        return brdfz_gpu.backend(request.param)
    except brdfz_gpu.BackendUnavailable as e:
        pytest.skip(f"the {request.param} backend cannot start: {e}")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    return exported_layouts(tmp_path_factory, RGL, {**SPECS, **LOBE_SAMPLED}, "gpu")


@pytest.mark.parametrize("name", SPECS)
def test_shaders_match_the_library(gpu, exported, name):
    from brdfz.gpu import TOLERANCE, check

    r = check(exported[name], gpu, n=PAIRS)
    assert r["eval"]["worst"] <= TOLERANCE, r
    assert r["pdf"]["worst"] <= TOLERANCE, r
    s = r["sample"]
    # sample() gives pdf() of the direction it drew, and f·cosθi/pdf with the same eval: the same code
    # on the same bits (to an ulp or two where a compiler fuses multiply-adds in one place only).
    assert s["pdf_vs_own_pdf"] <= 1e-6 and s["weight_vs_own_eval"] <= 1e-6, r
    assert s["pdf_vs_library"] <= TOLERANCE, r
    # The same u draws the library's wi: the GPU samples the library's density.
    assert s["same_draw"] > 0.999, r
    # Draws fail only below the horizon, as the library's do on the same wo and u.
    assert abs(s["failed"] - s["failed_library"]) <= PAIRS * 1e-4, r
    assert s["drawn"] > 0.99 * PAIRS, r
    assert r["ok"]


def test_check_finds_a_wrong_lookup(gpu, exported):
    """The comparison can fail: the same table read as if its samples lay at bin starts, not centres,
    is half a bin off, far beyond the tolerance."""
    from brdfz.gpu import TOLERANCE, Layout, check

    layout = Layout(exported["table_f16"])
    assert layout.desc["centre"][0] == 1
    layout.desc["centre"] = 0
    r = check(layout, gpu, n=2000)
    assert not r["ok"] and r["eval"]["worst"] > 100 * TOLERANCE


def test_command_line(gpu, exported, tmp_path):
    import subprocess
    import sys

    ok = subprocess.run([sys.executable, "-m", "brdfz.gpu", "check", str(exported["nmf"]), "--pairs", "2000", "--backend", gpu.name],
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0, ok.stderr
    assert "eval   worst relative error" in ok.stdout and "ok: worst" in ok.stdout
    # A file that is not a material is refused with a reason, not compared.
    model = tmp_path / "broken.brdfzrt"
    model.write_bytes(exported["nmf"].read_bytes()[:100])
    refused = subprocess.run([sys.executable, "-m", "brdfz.gpu", "check", str(model)], capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and str(model) in refused.stderr and refused.stderr.count("\n") == 1, refused.stderr


def test_webgl_reports_console_errors(gpu, exported):
    """What the page logs as an error fails the next call (WebGL errors fail the call itself: webgl.js)."""
    if gpu.name != "webgl":
        pytest.skip("the webgl backend's page")
    from brdfz.gpu import Layout

    gpu.page.evaluate("console.error('an error in the page')")
    with pytest.raises(RuntimeError, match="an error in the page"):
        gpu.bind(Layout(exported["nmf"]))


@pytest.mark.parametrize("name", LOBE_SAMPLED)
def test_lobe_samplers(gpu, exported, name):
    """Lobes drawn by their own samplers: eval and pdf within the tolerance, every draw's pdf and weight
    the backend's own, the library's draws, χ² of the draws. Lafortune's pdf against the library holds on
    all but a few pairs in 10^4: grazing pairs of nearly opposite azimuth, where the density folded from
    below the horizon (its lobe axis at wi mirrored) moves by up to 1.5e-4 when the float input's length,
    1 ± 3e-8, is normalised in double by the library and not by the shader (which keeps a draw's bits)."""
    if gpu.name != "wgpu":
        pytest.skip("on one backend: the shader code is the same on every backend (test_shaders_match_the_library)")
    import numpy as np

    from brdfz.gpu import TOLERANCE, Layout, check
    from brdfz.gpu.check import chi2, relative_error

    r = check(exported[name], gpu, n=PAIRS)
    s = r["sample"]
    assert s["pdf_vs_own_pdf"] <= 1e-6 and s["weight_vs_own_eval"] <= 1e-6, r
    assert s["same_draw"] > 0.999 and s["drawn"] > 0.99 * PAIRS, r
    if name != "lobes_sampled_lafortune":
        assert r["ok"], r
    else:
        assert r["eval"]["worst"] <= TOLERANCE and r["pdf"]["p99"] <= TOLERANCE, r
        brdfz = import_brdfz()
        lib = brdfz.load(exported[name])
        from brdfz.gpu.check import pairs

        wi, wo = pairs(PAIRS)
        err = relative_error(gpu.bind(Layout(exported[name])).pdf(wo, wi), lib.pdf(wo.astype(np.float64), wi.astype(np.float64)))
        assert np.mean(err > TOLERANCE) < 5e-4, np.sort(err)[-10:]
    _, _, p = chi2(exported[name], gpu, theta_o=45.0)
    assert p > 1e-3, p


@pytest.mark.parametrize("theta_o", [30.0, 75.0])
def test_gpu_sampler_passes_chi2(gpu, exported, theta_o):
    """The GPU's draws follow the GPU's pdf (Pearson's χ² over cells of equal solid angle), and the test
    tells draws from another wo's pdf apart."""
    if gpu.name != "wgpu":
        pytest.skip("χ² on one backend: the draws are the same code on every backend (test_shaders_match_the_library)")
    from brdfz.gpu.check import chi2

    _, _, p = chi2(exported["svd_cos_shared"], gpu, theta_o=theta_o)
    assert p > 1e-3, p
    _, _, p_other = chi2(exported["svd_cos_shared"], gpu, theta_o=theta_o, against=theta_o - 10)
    assert p_other < 1e-6, p_other
