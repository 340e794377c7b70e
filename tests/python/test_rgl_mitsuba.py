"""brdfz's RGL `.bsdf` evaluator against Mitsuba 3's `measured` plugin, the reference evaluator.

For every file in ../shared/data/rgl: 10,000 seeded random (wi, wo) pairs in the upper hemisphere,
evaluated by Mitsuba (scalar_rgb; si.wi = our wi, returns f·cosθo) and by `brdfz eval --pairs`
(returns f, no cosine). Per channel: |ours·cosθo − mitsuba| ≤ max(1e-3·|mitsuba|, 1e-5).
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

REPO = pathlib.Path(__file__).resolve().parents[2]
RGL_DIR = REPO.parent / "shared" / "data" / "rgl"
FILES = sorted(RGL_DIR.glob("*.bsdf")) if RGL_DIR.is_dir() else []
N_PAIRS = 10_000
REL_TOL, ABS_TOL = 1e-3, 1e-5


@pytest.fixture(scope="module")
def cli():
    path = os.environ.get("BRDFZ_CLI")
    if not path:
        pytest.skip("BRDFZ_CLI is not set (path of the brdfz command)")
    return path


def random_upper(rng, n):
    """Directions uniform over the upper hemisphere."""
    z = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * np.pi, n)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def mitsuba_eval(path, wi, wo):
    """f·cosθo from Mitsuba's `measured` plugin, one scalar call per pair (about 5 µs each)."""
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    out = np.empty((len(wi), 3))
    for k in range(len(wi)):
        si.wi = mi.Vector3f(*wi[k])
        v = bsdf.eval(ctx, si, mi.Vector3f(*wo[k]))
        out[k] = (v[0], v[1], v[2])
    return out


def brdfz_eval(cli, path, wi, wo, tmp_path):
    pairs = tmp_path / "pairs.csv"
    np.savetxt(pairs, np.hstack([wi, wo]), delimiter=",", fmt="%.17g")
    run = subprocess.run([cli, "eval", str(path), "--pairs", str(pairs)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    rows = [line for line in run.stdout.splitlines() if line.strip()]
    return np.array([[float(x) for x in line.split(",")] for line in rows])


@pytest.mark.parametrize("path", FILES or [None], ids=[p.name for p in FILES] or ["no-data"])
def test_rgl_matches_mitsuba(path, cli, tmp_path):
    if path is None:
        pytest.skip(f"skipped: ../shared missing ({RGL_DIR})")
    rng = np.random.default_rng(20181204)
    # Mitsuba works in float32: give both evaluators the same float32-representable directions, so
    # the comparison measures the evaluators, not the rounding of their inputs.
    wi = random_upper(rng, N_PAIRS).astype(np.float32).astype(np.float64)
    wo = random_upper(rng, N_PAIRS).astype(np.float32).astype(np.float64)

    ref = mitsuba_eval(path, wi, wo)
    ours = brdfz_eval(cli, path, wi, wo, tmp_path)
    assert ours.shape == ref.shape
    assert np.isfinite(ref).all(), "Mitsuba returned non-finite values"
    assert np.isfinite(ours).all()

    err = np.abs(ours * wo[:, 2:3] - ref)
    bad = err > np.maximum(REL_TOL * np.abs(ref), ABS_TOL)
    big = np.abs(ref) > 1e-4
    rel = (err[big] / np.abs(ref[big])).max() if big.any() else 0.0
    k = int(np.argmax(bad.any(axis=1))) if bad.any() else None
    assert not bad.any(), (
        f"{bad.any(axis=1).sum()} of {N_PAIRS} pairs outside tolerance; max abs {err.max():.3g}, "
        f"max rel (|ref| > 1e-4) {rel:.3g}; first: wi {wi[k]} wo {wo[k]} "
        f"ours·cos {ours[k] * wo[k, 2]} mitsuba {ref[k]}"
    )
