"""brdfz.plot's figures checked by their values: the data each figure draws equals the library's eval
(or albedo, or render) at the plotted points, the light and the mirror direction are on the sides they
should be, errors are masked beyond the reference's measured elevation; the renderer's environment
integral against known answers; the broadcasting eval and the angle helpers. Synthetic materials
(analytic model files) have known answers; the RGL and Cornell files come from ../shared."""
import json
import math

import numpy as np
import pytest

from conftest import SHARED, import_brdfz

brdfz = import_brdfz()
matplotlib = pytest.importorskip("matplotlib", reason="matplotlib is not installed (scripts/setup-deps)")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from brdfz import plot, report  # noqa: E402

RHO = np.array([0.2, 0.4, 0.6])


def model(path, name, parameters):
    path.write_text(json.dumps({"format": "brdfz-analytic", "version": 1, "model": name, "parameters": parameters}))
    return brdfz.load(path)


@pytest.fixture(scope="module")
def lambert(tmp_path_factory):
    return model(tmp_path_factory.mktemp("lambert") / "lambert.json", "lambert",
                 {f"lambert.rho_{c}": float(v) for c, v in zip("rgb", RHO)})


@pytest.fixture(scope="module")
def glossy(tmp_path_factory):
    p = {f"lambert.rho_{c}": 0.05 for c in "rgb"} | {f"ggx.ks_{c}": 1.0 for c in "rgb"}
    return model(tmp_path_factory.mktemp("glossy") / "glossy.json", "lambert+ggx", p | {"ggx.alpha": 0.08, "ggx.f0": 0.5})


@pytest.fixture(scope="module")
def rgl():
    path = SHARED / "data" / "rgl" / "ilm_l3_37_metallic_rgb.bsdf"
    if not path.exists():
        pytest.skip("../shared/data/rgl is missing")
    return brdfz.load(path)


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def below_normal(s_deg, plane_deg=0.0):
    """wo at signed in-plane elevations s (degrees), written out: positive s away from a light at azimuth 0."""
    s, p = np.radians(s_deg), math.radians(plane_deg)
    return np.stack([-np.sin(s) * math.cos(p), -np.sin(s) * math.sin(p), np.cos(s)], axis=-1)


# ------------------------------------------------------------------------------------- eval, helpers

def test_eval_broadcasts_over_leading_dimensions(glossy):
    rng = np.random.default_rng(1)
    wi = np.abs(rng.normal(size=(4, 5, 3)))
    wo = np.array([0.1, -0.2, 0.9])
    flat = glossy.eval(wi.reshape(-1, 3), np.tile(wo, (20, 1)))
    assert np.array_equal(glossy.eval(wi, wo), flat.reshape(4, 5, 3))
    assert np.array_equal(glossy.eval_cos(wi, wo), glossy.eval_cos(wi.reshape(-1, 3), np.tile(wo, (20, 1))).reshape(4, 5, 3))
    assert glossy.pdf(wo, wi).shape == (4, 5)
    one = glossy.eval([0.3, 0.0, 1.0], (0, 0, 1))  # lists and tuples, one pair -> (3,)
    assert one.shape == (3,) and np.array_equal(one, glossy.eval(np.array([[0.3, 0, 1.0]]), np.array([[0.0, 0, 1]]))[0])
    p = glossy.pdf([0.0, 0.0, 1.0], [0.3, 0.0, 1.0])
    assert np.ndim(p) == 0 and p == glossy.pdf(np.array([[0.0, 0, 1]]), np.array([[0.3, 0, 1.0]]))[0] and p > 0
    assert glossy.eval(wi[:, :1], wi[:1]).shape == (4, 5, 3)  # (4, 1, 3) against (1, 5, 3)


@pytest.mark.parametrize("wi, wo, message", [
    (np.zeros((2, 3, 3)) + 1, np.zeros((4, 3)) + 1, r"shapes do not broadcast: wi \(2, 3, 3\) and wo \(4, 3\)"),
    (np.zeros((5, 3)) + 1, np.zeros((4, 3)) + 1, r"wi and wo have different lengths \(5 and 4\)"),
    ([0.0, 1.0], [0.0, 0.0, 1.0], r"wi: expected shape \(\.\.\., 3\), got \(2,\)"),
    ([[0, 0, 1], [0, 1]], [0.0, 0.0, 1.0], r"wi: expected a numpy array, list or tuple of shape \(\.\.\., 3\)"),
    ("up", [0.0, 0.0, 1.0], r"wi: expected a numpy array, list or tuple"),
    ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], r"wi\[0\]: direction must be a finite non-zero vector"),
])
def test_bad_direction_arguments_are_one_line_value_errors(glossy, wi, wo, message):
    with pytest.raises(ValueError, match=message):
        glossy.eval(wi, wo)


def test_directions_and_rusinkiewicz_angles():
    theta, phi = np.radians([[10.0], [50.0], [80.0]]), np.radians([0.0, 45.0, 200.0, -30.0])
    d = brdfz.directions(theta, phi)
    assert d.shape == (3, 4, 3)
    assert np.allclose(d, np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                                       np.cos(theta)), axis=-1))
    assert brdfz.directions(0.0, 1.0).shape == (3,)
    # The mirror pair: half vector on the normal, difference elevation θ.
    th, ph, td, pd = brdfz.to_half_diff(brdfz.directions(0.6, 0.0), brdfz.directions(0.6, math.pi))
    assert abs(th) < 1e-12 and abs(td - 0.6) < 1e-12
    rng = np.random.default_rng(2)
    angles = rng.uniform([0.01, 0.01, -3.1, -3.1], [1.5, 1.5, 3.1, 3.1], size=(200, 4))
    wi, wo = brdfz.from_half_diff(angles[:, 0], angles[:, 1], angles[:, 2], angles[:, 3])
    back = np.stack(brdfz.to_half_diff(wi, wo), axis=-1)  # (θh, φh, θd, φd)
    assert np.allclose(back[:, [0, 2, 3, 1]], angles, atol=1e-9)
    with pytest.raises(ValueError, match=r"theta\[1\]: angle must be finite"):
        brdfz.directions([0.1, math.nan], 0.0)
    with pytest.raises(ValueError, match="phi: expected a numpy array, list or tuple of real numbers"):
        brdfz.directions(0.1, "east")


def test_measured_theta_max(lambert, rgl):
    assert lambert.measured_theta_max == math.pi / 2
    assert math.radians(60) < rgl.measured_theta_max < math.pi / 2


def test_scattered_measurements_as_arrays():
    cornell = SHARED / "data" / "cornell" / "cayman.brdf"
    alta = SHARED / "data" / "alta" / "retro-gray-tape.dat"
    if not cornell.exists() or not alta.exists():
        pytest.skip("../shared/data/cornell or alta is missing")
    m = brdfz.load_measurements(cornell)
    assert m.wi.shape == m.wo.shape == m.f.shape and m.wi.shape[1] == 3 and len(m.f) > 1000 and m.channels == 3
    assert np.allclose(np.linalg.norm(m.wi, axis=1), 1) and (m.wi[:, 2] > 0).all() and (m.wo[:, 2] > 0).all()
    a = brdfz.load_measurements(alta)
    assert a.channels == 1 and np.array_equal(a.f[:, 0], a.f[:, 2]) and (a.f >= 0).all()
    # The arrays are what metrics() judges at: a constant model's error follows from them alone.
    flat = brdfz.load_measurements(cornell)
    assert "cayman" in flat.source
    with pytest.raises(brdfz.UnsupportedError):
        brdfz.load_measurements(SHARED / "data" / "rgl" / "paper_white_rgb.bsdf")


# ---------------------------------------------------------------------------------------------- polar

def test_polar_plots_eval_with_the_light_left_and_the_peak_at_the_mirror(glossy):
    fig = plot.polar({"glossy": glossy}, theta_i=[40], samples=361)
    ax = fig.axes[0]
    line = ax.lines[0]
    s = np.degrees(line.get_xdata())
    wi = np.array([math.sin(math.radians(40)), 0.0, math.cos(math.radians(40))])
    expected = glossy.eval(np.tile(wi, (len(s), 1)), below_normal(s)).mean(axis=1)
    assert np.allclose(line.get_ydata(), expected, rtol=1e-12, atol=0)
    peak = np.argmax(line.get_ydata())
    assert abs(s[peak] - 40) <= 0.5  # the mirror direction
    # On the figure: the peak right of the normal, the light (the star) left of it.
    centre = ax.transData.transform((0.0, 0.0))[0]
    light = next(l for l in ax.lines if l.get_label() == "light")
    assert ax.transData.transform((line.get_xdata()[peak], line.get_ydata()[peak]))[0] > centre + 20
    assert ax.transData.transform((light.get_xdata()[0], light.get_ydata()[0]))[0] < centre - 20


def test_polar_any_plane_and_log(glossy, lambert):
    fig = plot.polar([glossy, lambert], theta_i=[0, 30], plane=90, log=True, channel="g", samples=91)
    assert len(fig.axes) == 2 and fig.axes[0].get_yscale() == "log"
    for ax, b in zip(fig.axes, (glossy, lambert)):
        for line, t in zip(ax.lines, (0, 30)):
            s = np.degrees(line.get_xdata())
            wi = brdfz.directions(math.radians(t), 0.0)
            assert np.allclose(line.get_ydata(), b.eval(wi, below_normal(s, 90))[:, 1], rtol=1e-12)
    assert np.allclose(fig.axes[1].lines[0].get_ydata()[1:-1], RHO[1] / math.pi)
    assert not any(l.get_label() == "light" for l in fig.axes[0].lines)  # the light is not in that plane
    # The log radius spans the values drawn.
    assert plot.polar(lambert, log=True).axes[0].get_ylim()[1] == pytest.approx(1.5 * RHO.mean() / math.pi)


def test_polar_error_masked_beyond_the_measured_elevation(rgl):
    small = brdfz.compress(rgl, "tabular:res=16x16x32,symmetry=none")
    fig = plot.polar({"measured": rgl, "table": small}, theta_i=[30, 88], error="signed", samples=61)
    near, far = fig.axes[0].lines[:2]
    assert math.radians(88) > rgl.measured_theta_max and np.isnan(far.get_ydata()).all()
    wi = brdfz.directions(math.radians(30), 0.0)
    wo = below_normal(near.get_xdata())
    assert np.allclose(near.get_ydata(), (small.eval(wi, wo) - rgl.eval(wi, wo)).mean(axis=1), atol=1e-12)
    assert np.abs(near.get_ydata()).max() > 0


def test_polar_with_measurements_over_it(lambert):
    cornell = SHARED / "data" / "cornell" / "cayman.brdf"
    if not cornell.exists():
        pytest.skip("../shared/data/cornell is missing")
    m = brdfz.load_measurements(cornell)
    ti = float(np.round(np.degrees(np.arccos(m.wi[len(m.wi) // 2, 2]))))
    fig = plot.polar(lambert, theta_i=[ti], measurements=m, tolerance=6)
    assert fig.axes[0].get_title().startswith("analytic lambert") and len(fig.axes[0].get_title().split("\n")[0]) <= 40
    dots = fig.axes[0].collections[0]
    plotted = dots.get_offsets()
    assert len(plotted) > 3
    # Every dot is one of the measurements near that incidence, at its own value and elevation.
    values = m.f.mean(axis=1)
    near = np.abs(np.degrees(np.arccos(m.wi[:, 2])) - ti) <= 6
    for a, v in plotted:
        k = np.flatnonzero(near & np.isclose(values, v, rtol=1e-12, atol=0))
        assert k.size and np.isclose(np.degrees(np.arccos(m.wo[k, 2])), abs(math.degrees(a)), atol=1e-6).any()


# --------------------------------------------------------------------------------------------- slices

def test_theta_h_theta_d_image_is_eval_on_the_grid(glossy, lambert):
    fig = plot.theta_h_theta_d({"glossy": glossy, "lambert": lambert}, phi_d=0.0, res=30, log=True)
    image = fig.axes[0].images[0]
    assert image.get_extent() == [0, 90, 0, 90]
    data = image.get_array()
    axis = (np.arange(30) + 0.5) * 3
    wi, wo = brdfz.from_half_diff(np.radians(axis)[None, :], np.radians(axis)[:, None], 0.0)
    expected = glossy.eval(wi, wo).mean(axis=-1)  # rows θd, columns θh
    assert np.allclose(data.filled(0), expected, rtol=1e-12)
    # Log scale: pairs below the horizon (θh + θd > 90° at φd = 0) are 0, masked.
    total = axis[None, :] + axis[:, None]
    assert np.array_equal(data.mask, expected <= 0) and data.mask[total > 90.01].all() and not data.mask[total < 89.99].any()
    assert data[5, 0] > data[5, 10]  # the specular peak at θh = 0
    assert np.allclose(fig.axes[1].images[0].get_array().compressed(), RHO.mean() / math.pi)


def test_theta_h_phi_d_image_and_its_error_mask(rgl):
    small = brdfz.compress(rgl, "tabular:res=16x16x32,symmetry=none")
    fig = plot.theta_h_phi_d({"measured": rgl, "table": small}, theta_d=60, res=(30, 24), error="relative")
    data = fig.axes[0].images[0].get_array()
    assert data.shape == (24, 30)
    th, pd = (np.arange(30) + 0.5) * 3, (np.arange(24) + 0.5) * 15
    wi, wo = brdfz.from_half_diff(np.radians(th)[None, :], math.radians(60), np.radians(pd)[:, None])
    a, b = rgl.eval(wi, wo).mean(axis=-1), small.eval(wi, wo).mean(axis=-1)
    beyond = np.arccos(np.clip(wi[..., 2], -1, 1)) > rgl.measured_theta_max
    assert beyond.any() and (~beyond).any()
    assert (data.mask[beyond]).all()
    keep = ~beyond & (a > 0)
    assert np.allclose(data[keep], (b[keep] - a[keep]) / a[keep], rtol=1e-9)
    plain = plot.theta_h_phi_d(rgl, theta_d=60, res=(30, 24), log=False).axes[0].images[0].get_array()
    assert np.allclose(np.ma.filled(plain, 0), a, rtol=1e-12)


# --------------------------------------------------------------------------------------------- albedo

def test_albedo_curves_and_their_error(lambert, glossy, tmp_path):
    fig = plot.albedo({"lambert": lambert, "glossy": glossy}, theta=[0, 30, 60, 85])
    lines = fig.axes[0].lines
    assert np.allclose(lines[0].get_ydata(), RHO.mean(), atol=1e-5)
    assert np.allclose(lines[1].get_ydata(), brdfz.albedo(glossy, np.radians([0, 30, 60, 85])).mean(axis=1))
    half = model(tmp_path / "half.json", "lambert", {f"lambert.rho_{c}": float(v / 2) for c, v in zip("rgb", RHO)})
    e = plot.albedo([half, lambert], error="relative").axes[0].lines[0].get_ydata()
    assert np.allclose(e, 1.0, atol=1e-5)


# --------------------------------------------------------------------------------------------- sphere

def test_sphere_environment_integral_has_its_known_answer(lambert):
    # A Lambertian under a uniform environment of radiance 1 reflects ρ everywhere: the mean of its
    # sampler's weights (exactly ρ for a cosine-weighted sampler, within its spread for another).
    image = report.render_sphere(lambert, 24, 256, irradiance=0.0, environment=lambda d: np.ones_like(d))
    u = (np.arange(24) + 0.5) / 24 * 2 - 1
    r2 = u[None, :] ** 2 + u[:, None] ** 2
    assert np.allclose(image[r2 < 0.9], RHO, rtol=0.02)
    assert np.allclose(image[r2 < 0.9].mean(axis=0), RHO, rtol=0.005)
    assert (image[r2 >= 1] == 0).all()


def test_sphere_has_no_point_artefacts_on_a_glossy_material(glossy):
    # The environment alone: 64 importance-sampled draws per pixel against 1024, and against what a
    # fixed set of 64 sky directions (the former renderer) gives, which leaves a dot per direction.
    kwargs = dict(irradiance=0.0)
    ours = report.render_sphere(glossy, 40, 64, **kwargs)
    reference = report.render_sphere(glossy, 40, 1024, seed=7, **kwargs)
    inside = reference.sum(axis=2) > 0
    k = np.arange(64) + 0.5
    z = 1 - 2 * k / 64
    phi = k * math.pi * (3 - math.sqrt(5))
    dirs = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], axis=1)
    u = (np.arange(40) + 0.5) / 40 * 2 - 1
    x, y = np.meshgrid(u, -u)
    n = np.stack([x, y, np.sqrt(np.clip(1 - x * x - y * y, 0, None))], axis=-1)[inside]
    fixed = np.zeros_like(n)
    for d, L in zip(dirs, report.sky(dirs)):
        # An isotropic material: any tangent frame about the normal gives the same values.
        wo_w = np.broadcast_to([0.0, 0.0, 1.0], n.shape)
        t = np.cross(n, [0.0, 1.0, 0.0])
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        b = np.cross(n, t)
        local = lambda v: np.stack([(v * t).sum(1), (v * b).sum(1), (v * n).sum(1)], axis=1)  # noqa: E731
        fixed += glossy.eval_cos(local(np.broadcast_to(d, n.shape)), local(wo_w)) * L * (4 * math.pi / 64)

    def rel(a):
        return np.sqrt(np.mean((a - reference[inside]) ** 2)) / np.sqrt(np.mean(reference[inside] ** 2))

    assert rel(ours[inside]) < 0.05
    assert rel(fixed) > 3 * rel(ours[inside])


def test_sphere_figure_and_its_error(glossy, lambert, rgl):
    fig = plot.sphere({"glossy": glossy, "lambert": lambert}, size=24, samples=4)
    rendered = report.render_sphere(glossy, 24, 4)
    assert np.allclose(fig.axes[0].images[0].get_array(), report.tone_map(rendered, report.exposure_of(rendered)))
    small = brdfz.compress(rgl, "tabular:res=16x16x32,symmetry=none")
    light = [0.95, 0.0, 0.3]
    fig = plot.sphere({"measured": rgl, "table": small}, size=24, samples=2, light=light, error="signed")
    data = fig.axes[0].images[0].get_array()
    beyond = plot.sun_elevation(24, light) > rgl.measured_theta_max
    u = (np.arange(24) + 0.5) / 24 * 2 - 1
    inside = u[None, :] ** 2 + u[:, None] ** 2 < 1
    assert (beyond & inside).any() and data.mask[beyond].all() and not data.mask[inside & ~beyond].all()


# ------------------------------------------------------------------------------------------ bad input

@pytest.mark.parametrize("call, error", [
    (lambda b: plot.polar(b, theta_i=[100]), ValueError),
    (lambda b: plot.polar(b, samples=1), ValueError),
    (lambda b: plot.polar(b, channel="alpha"), ValueError),
    (lambda b: plot.polar(b, error="absolute"), ValueError),
    (lambda b: plot.polar(b, error="signed"), ValueError),  # no second material
    (lambda b: plot.theta_h_theta_d(b, res=1), ValueError),
    (lambda b: plot.theta_h_phi_d(b, theta_d=math.nan), ValueError),
    (lambda b: plot.albedo([]), ValueError),
    (lambda b: plot.albedo([b, None]), TypeError),
    (lambda b: plot.sphere(b, size=0), ValueError),
    (lambda b: plot.sphere(b, light=[0, 0, 0]), ValueError),
])
def test_bad_arguments(lambert, call, error):
    with pytest.raises(error) as e:
        call(lambert)
    assert "\n" not in str(e.value)
