"""python -m brdfz.examples.realtime: a sphere rendered on the GPU by an application shader through
brdfz.slang (wgpu; Mesa's lavapipe where there is no GPU) against the C++ library's render with the
same draws, at 256², on a ≤ 16 KB factorisation and a lobe mixture of a real RGL file; a material
against another's reference, or with other draws, falls below the threshold; bad input is a one-line
error."""

import importlib.util
import re
import subprocess
import sys

import pytest

from conftest import SHARED, import_brdfz

RGL = SHARED / "data" / "rgl" / "cc_ibiza_sunset_rgb.bsdf"
SPECS = {
    "svd": "svd:rank=10,space=cos,colour=shared,res=25x20x14,dwarp=0.9,fit=lsq,symmetry=bilateral,dtype=f16",
    "lobes": "analytic:lambert+ggx,starts=2",
}
SIZE = 256
DRAWS = 16  # of the environment per pixel: the same u on both sides, so few suffice


@pytest.fixture(scope="module")
def gpu():
    import_brdfz()
    if not RGL.exists():
        pytest.skip(f"../shared is missing ({RGL})")
    if importlib.util.find_spec("slangpy") is None:
        pytest.skip("the Slang compiler (the slangpy wheel) is not installed")
    from brdfz.examples import realtime
    from brdfz.gpu import BackendUnavailable

    try:
        return realtime.SphereRenderer()
    except BackendUnavailable as e:
        pytest.skip(f"wgpu cannot start: {e}")


@pytest.fixture(scope="module")
def renders(gpu, tmp_path_factory):
    """Per spec: (its representation's bytes, its .brdfzrt, the GPU image, the CPU reference)."""
    brdfz = import_brdfz()
    from brdfz.examples import realtime
    from brdfz.gpu import Layout

    out = tmp_path_factory.mktemp("realtime")
    source = brdfz.load(RGL)
    result = {}
    for name, spec in SPECS.items():
        compressed = brdfz.compress(source, spec)
        path = out / f"{name}.brdfzrt"
        brdfz.export(compressed, path)
        image = gpu.render(Layout(path), SIZE, DRAWS)
        result[name] = (compressed.nbytes, path, image, realtime.reference(brdfz.load(path), SIZE, DRAWS))
    return result


def test_factorisation_fits_in_16_kb(renders):
    assert renders["svd"][0] <= 16384


@pytest.mark.parametrize("name", SPECS)
def test_gpu_render_matches_the_library(renders, name):
    from brdfz.examples import realtime

    _, _, image, ref = renders[name]
    assert image.shape == ref.shape == (SIZE, SIZE, 3)
    assert (image[~realtime.sphere_mask(SIZE)] == 0).all()
    assert realtime.psnr(image, ref) >= realtime.MIN_PSNR


def test_another_materials_reference_fails(renders):
    from brdfz.examples import realtime

    assert realtime.psnr(renders["svd"][2], renders["lobes"][3]) < realtime.MIN_PSNR - 15
    assert realtime.psnr(renders["lobes"][2], renders["svd"][3]) < realtime.MIN_PSNR - 15


def test_the_draws_are_the_references(gpu, renders):
    # Other u on the GPU leave the glossy lobes' Monte Carlo noise, which the shared u take out.
    from brdfz.examples import realtime
    from brdfz.gpu import Layout

    _, path, _, ref = renders["lobes"]
    assert realtime.psnr(gpu.render(Layout(path), SIZE, DRAWS, seed=2), ref) < realtime.MIN_PSNR


def _run(*args):
    return subprocess.run([sys.executable, "-m", "brdfz.examples.realtime", *map(str, args)], capture_output=True,
                          text=True, timeout=300)


def test_command_on_a_runtime_layout(renders, tmp_path):
    png = tmp_path / "sphere.png"
    r = _run(renders["svd"][1], "--size", 64, "--env-samples", 4, "--png", png)
    assert r.returncode == 0, r.stderr
    assert float(re.search(r"PSNR ([\d.]+|inf) dB", r.stdout).group(1)) >= 40
    assert png.stat().st_size > 0


def test_missing_file_is_a_one_line_error(tmp_path):
    import_brdfz()
    r = _run(tmp_path / "missing.bsdf")
    assert r.returncode != 0
    assert "Traceback" not in r.stderr
    errors = [line for line in r.stderr.splitlines() if line.startswith("brdfz.examples.realtime:")]
    assert len(errors) == 1 and "missing.bsdf" in errors[0], r.stderr
