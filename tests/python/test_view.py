"""brdfz view (python -m brdfz.view) in a real browser: headless Chromium (Debian's, driven by
Playwright) opens the --html page from disk and the served page, on two real RGL files (a glossy car
paint and a matte paper) and the paint's ≤ 16 KB factorisation. The spheres the page renders with
WebGPU (SwiftShader here), the means of their passes, match the C++ library's renders with the same
light and draws, also after the light is moved with the mouse and another file is picked, and not
another material's; the polar plot's and the θh × θd image's values are eval's at their points; no
console errors; the page of two measured files stays under 8 MB. Screenshots go to the test's tmp dir
and to $BRDFZ_TEST_ARTEFACTS when set. Bad input is a one-line error without a page."""

import importlib.util
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import SHARED, import_brdfz

RGL = SHARED / "data" / "rgl" / "cc_ibiza_sunset_rgb.bsdf"
MATTE = SHARED / "data" / "rgl" / "paper_white_rgb.bsdf"
SPEC = "svd:rank=10,space=cos,colour=shared,res=25x20x14,dwarp=0.9,fit=lsq,symmetry=bilateral,dtype=f16"
CHROMIUM = "/usr/bin/chromium"
# WebGPU on SwiftShader (Vulkan on the CPU) where there is no GPU.
FLAGS = ["--enable-unsafe-webgpu", "--use-webgpu-adapter=swiftshader", "--enable-unsafe-swiftshader"]
SIZE, DRAWS, PASSES = 96, 8, 3
MAX_PAGE_BYTES = 8 << 20
MIN_PSNR = 35.0


def _view_command(cli, *args):
    """`brdfz view` when the built CLI is given (it runs this Python), else python -m brdfz.view."""
    return [cli, "view", *args] if cli else [sys.executable, "-m", "brdfz.view", *args]


def _env():
    return dict(os.environ, BRDFZ_PYTHON_EXECUTABLE=sys.executable)


@pytest.fixture(scope="module")
def browser():
    import_brdfz()
    if not RGL.exists():
        pytest.skip(f"../shared is missing ({RGL})")
    if importlib.util.find_spec("slangpy") is None:
        pytest.skip("the Slang compiler (the slangpy wheel) is not installed")
    if importlib.util.find_spec("playwright") is None:
        pytest.skip("playwright is not installed (pip install playwright)")
    if not os.path.exists(CHROMIUM):
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def materials(browser, tmp_path_factory):
    """The page's materials as the library reads them: (Brdf plotted, runtime layout the sphere
    renders), in the page's order: the two files, then the paint's factorisation."""
    brdfz = import_brdfz()
    from brdfz import view

    out = tmp_path_factory.mktemp("view-materials")
    source = brdfz.load(RGL)
    compressed = brdfz.compress(source, SPEC)
    assert compressed.nbytes <= 16384
    result = []
    for k, brdf in enumerate([source, brdfz.load(MATTE), compressed]):
        layout = view.sphere_layout(brdf, out / f"{k}.brdfzrt")
        # A measured file's sphere draws its float16 table, φd whole (RGL files are not reciprocal).
        assert layout["describe"].startswith("tabular 90x90x180, symmetry bilateral float16") == (k < 2), layout
        result.append((brdf, brdfz.load(layout["path"])))
    return result


@pytest.fixture(scope="module")
def pages(browser, tmp_path_factory):
    """{"file": the --html page opened from disk, "served": the page python -m brdfz.view --port 0
    serves}, each with the list its console errors land in, once their spheres are rendered. Built and
    opened together: most of the time goes into SwiftShader compiling the sphere's pipeline."""
    out = tmp_path_factory.mktemp("view") / "view.html"
    cli = os.environ.get("BRDFZ_CLI") if os.path.exists(os.environ.get("BRDFZ_CLI", "")) else None
    args = [str(RGL), str(MATTE), "--compare", SPEC, "--size", str(SIZE), "--env-samples", str(DRAWS),
            "--passes", str(PASSES)]
    server = subprocess.Popen([sys.executable, "-m", "brdfz.view", *args], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True, env=_env())
    try:
        p = subprocess.run(_view_command(cli, *args, "--html", str(out)), capture_output=True, text=True, env=_env(),
                           timeout=300)
        assert p.returncode == 0, p.stderr
        assert "views 100%" in p.stderr and "no sphere" not in p.stderr  # progress lines for the long steps
        assert out.exists() and "wrote" in p.stdout
        print(f"page of two RGL files and a factorisation: {out.stat().st_size:,} bytes")
        assert out.stat().st_size < MAX_PAGE_BYTES
        opened = {"file": _open(browser, out.as_uri())}
        line = server.stdout.readline()
        assert line.startswith("serving http://127.0.0.1:"), line
        opened["served"] = _open(browser, line.split()[1])
        for page, _ in opened.values():
            page.wait_for_function("window.brdfzView && window.brdfzView.ready", timeout=120_000)
            page.evaluate("window.brdfzView.ready")
            page.evaluate("window.brdfzView.idle()")
            if page.evaluate("window.brdfzView.gpu()") is None:
                pytest.skip(f"WebGPU cannot start in this Chromium: {page.evaluate('window.brdfzView.error()')}")
        yield opened
        for page, _ in opened.values():
            page.close()
    finally:
        server.terminate()
        server.wait(timeout=30)


def _artefacts(page, tmp_path, name):
    path = tmp_path / f"{name}.png"
    page.screenshot(path=path, full_page=True)
    folder = os.environ.get("BRDFZ_TEST_ARTEFACTS")
    if folder:
        os.makedirs(folder, exist_ok=True)
        shutil.copy(path, os.path.join(folder, path.name))


def _open(browser, url):
    """A page at `url`, loaded (its spheres render on), and the list its console errors land in."""
    page = browser.new_page(viewport={"width": 1280, "height": 1400})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    return page, errors


def _sphere(page, which):
    s = page.evaluate(f"window.brdfzView.sphere('{which}')")
    return s, np.array(s["pixels"], np.float32).reshape(s["size"], s["size"], 3)


def _reference(rt, s):
    """The library's render of the page's sphere: the mean of its passes, pass p with seed + p."""
    from brdfz import report
    from brdfz.examples import realtime

    return np.mean([report.render_sphere(rt, s["size"], s["env_samples"], light=s["light"],
                                         draws=realtime.draws(s["env_samples"], s["seed"] + p))
                    for p in range(s["passes"])], axis=0)


def _psnrs(page, materials, picked=(0, 2), other=1):
    """PSNR of A's and B's spheres (the materials `picked`) against their own references, and of A's
    against the material `other`'s."""
    from brdfz.examples import realtime

    result = {}
    for which, k in zip("ab", picked):
        s, image = _sphere(page, which)
        assert (s["size"], s["env_samples"], s["material"], s["passes"]) == (SIZE, DRAWS, k, PASSES)
        assert (image[~realtime.sphere_mask(SIZE)] == 0).all()
        result[which] = realtime.psnr(image, _reference(materials[k][1], s))
        if which == "a":
            result["a-against-other"] = realtime.psnr(image, _reference(materials[other][1], s))
    return result


def test_html_page_from_disk(pages, materials, tmp_path):
    brdfz = import_brdfz()
    from brdfz import plot

    page, errors = pages["file"]
    assert page.evaluate("window.brdfzView.materials")[2].startswith("svd")
    _artefacts(page, tmp_path, "view-file")
    before = _psnrs(page, materials)
    assert before["a"] >= MIN_PSNR and before["b"] >= MIN_PSNR, before
    assert before["a-against-other"] < MIN_PSNR, before  # the check can fail

    # The polar plot's values: eval's at its points, as the page gets them (float32 r, g, b) and
    # averages them (in double).
    for which, (brdf, _) in zip("ab", (materials[0], materials[2])):
        polar = page.evaluate(f"window.brdfzView.polar('{which}')")
        wi = brdfz.directions(np.radians(polar["theta_i"]), 0.0)
        wo = plot.plane_directions(0.0, 0.0, np.array(polar["angles"]))[1]
        rgb = brdf.eval(wi[:, None, :], wo[None, :, :]).astype(np.float32).astype(float)
        expected = (rgb[..., 0] + rgb[..., 1] + rgb[..., 2]) / 3
        np.testing.assert_allclose(np.reshape(polar["values"], expected.shape), expected, rtol=1e-15, atol=0)
        # The θh × θd image: the mean of r, g, b at its bin centres, sent as float32.
        image = page.evaluate(f"window.brdfzView.slice('{which}')")
        centres = np.radians((np.arange(image["bins"]) + 0.5) * 90 / image["bins"])
        pairs = brdfz.from_half_diff(centres[None, :], centres[:, None], np.radians(image["phi_d"]))
        expected = brdf.eval(*pairs).mean(axis=-1).astype(np.float32)
        np.testing.assert_array_equal(np.reshape(image["values"], expected.shape).astype(np.float32), expected)

    # The error panels: relative by default, B − A on request (where A is tiny, a large relative error
    # may not matter); the polar panel's errors are those of the plotted values.
    a, b = (np.array(page.evaluate(f"window.brdfzView.polar('{w}')")["values"]) for w in "ab")
    for mode, expected in (("relative", (b - a) / a), ("absolute", b - a)):
        page.select_option("#pick-error", mode)
        shown = page.evaluate("window.brdfzView.polarError()")
        assert shown["mode"] == mode and shown["materials"] == [0, 2]
        np.testing.assert_allclose(shown["values"], expected, rtol=1e-15, atol=0)
    assert page.locator("#head-e").inner_text().startswith("absolute")
    page.select_option("#pick-error", "relative")

    # Dragging on the sphere moves the sun: a new image, still the library's.
    old_light, old = page.evaluate("window.brdfzView.light()"), _sphere(page, "a")[1]
    box = page.locator("#sphere-a").bounding_box()
    page.mouse.move(box["x"] + 0.75 * box["width"], box["y"] + 0.3 * box["height"])
    page.mouse.down()
    page.mouse.up()
    page.evaluate("window.brdfzView.idle()")
    s, moved = _sphere(page, "a")
    assert np.linalg.norm(np.subtract(s["light"], old_light)) > 0.5 and s["light"][0] > 0.3
    assert not np.allclose(moved, old)
    after = _psnrs(page, materials)
    assert after["a"] >= MIN_PSNR and after["b"] >= MIN_PSNR, after
    _artefacts(page, tmp_path, "view-file-light-moved")

    # The other file as A: its sphere and its polar plot.
    page.select_option("#pick-a", "1")
    page.evaluate("window.brdfzView.idle()")
    other = _psnrs(page, materials, picked=(1, 2), other=0)
    assert other["a"] >= MIN_PSNR and other["b"] >= MIN_PSNR and other["a-against-other"] < MIN_PSNR, other
    polar = page.evaluate("window.brdfzView.polar('a')")
    wi = brdfz.directions(np.radians(polar["theta_i"]), 0.0)
    wo = plot.plane_directions(0.0, 0.0, np.array(polar["angles"]))[1]
    rgb = materials[1][0].eval(wi[:, None, :], wo[None, :, :]).astype(np.float32).astype(float)
    assert polar["material"] == 1
    expected = (rgb[..., 0] + rgb[..., 1] + rgb[..., 2]) / 3
    np.testing.assert_allclose(np.reshape(polar["values"], expected.shape), expected, rtol=1e-15, atol=0)
    _artefacts(page, tmp_path, "view-file-matte")
    print(f"PSNR A {before['a']:.1f}, B {before['b']:.1f} dB; light moved: A {after['a']:.1f}, B {after['b']:.1f} dB; "
          f"A against the matte file's reference {before['a-against-other']:.1f} dB; the matte file as A: {other['a']:.1f} dB")
    assert errors == []


def test_served_page(pages, materials, tmp_path):
    page, errors = pages["served"]
    assert page.url.startswith("http://127.0.0.1:")
    result = _psnrs(page, materials)
    assert result["a"] >= MIN_PSNR and result["b"] >= MIN_PSNR, result
    _artefacts(page, tmp_path, "view-served")
    assert errors == []


@pytest.mark.parametrize("case", ["missing file", "bad spec"])
@pytest.mark.parametrize("how", ["python", "cli"])
def test_bad_input_is_one_line_without_a_page(how, case, tmp_path):
    import_brdfz()
    cli = os.environ.get("BRDFZ_CLI")
    if how == "cli" and not (cli and os.path.exists(cli)):
        pytest.skip("BRDFZ_CLI is not set to the built brdfz command")
    out = tmp_path / "view.html"
    if case == "missing file":
        args, named = [str(tmp_path / "missing.bsdf")], "missing.bsdf"
    else:
        if not RGL.exists():
            pytest.skip(f"../shared is missing ({RGL})")
        args, named = [str(RGL), "--compare", "svd:rank=0"], "rank"
    p = subprocess.run(_view_command(cli if how == "cli" else None, *args, "--html", str(out)),
                       capture_output=True, text=True, env=_env(), timeout=120)
    assert p.returncode == 1
    assert len(p.stderr.strip().splitlines()) == 1 and named in p.stderr and "Traceback" not in p.stderr, p.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []
