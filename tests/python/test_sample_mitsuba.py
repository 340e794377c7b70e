"""brdfz's GGX and Beckmann visible-normal samplers against Mitsuba 3's MicrofacetDistribution.

`brdfz sample MODEL.json` draws wi for a one-lobe model and prints its pdf. brdfz draws h from the
visible normals of wo, reflects wo about it, and folds a direction drawn below the horizon back up
(z -> -z), so its pdf is q(wi) + q(wi with -z), with q(w) = D_wo(h) / (4 wo.h), h = (wo + w)/|wo + w|
(sample/lobes.h). Mitsuba's `MicrofacetDistribution(..., sample_visible=True).pdf(wo, h)` is D_wo(h)
(its first argument is our wo), computed independently in float32: the pdfs must agree to 1e-4 for
GGX. For Beckmann, Mitsuba's G1 is Walter et al.'s rational approximation (< 0.35% off the exact G1
brdfz normalises with), so the tolerance there is 0.5%.
"""
import json

import numpy as np
import pytest

from conftest import run

mi = pytest.importorskip("mitsuba")

N = 2000


def brdfz_samples(cli, tmp_path, model, params, wo):
    path = tmp_path / "model.json"
    path.write_text(json.dumps({"format": "brdfz-analytic", "version": 1, "model": model, "parameters": params}))
    proc = run(cli, "sample", path, "--wo", ",".join(f"{x:.17g}" for x in wo), "-n", N, "--seed", 3)
    rows = np.array([[float(x) for x in line.split(",")] for line in proc.stdout.splitlines()[1:] if line.strip()])
    return rows[:, 0:3], rows[:, 3]


def mitsuba_pdf(distribution, alpha, wo, wi):
    """q(wi) + q(wi with -z), from Mitsuba's visible-normal density."""
    mi.set_variant("scalar_rgb")
    d = mi.MicrofacetDistribution(getattr(mi.MicrofacetType, distribution), alpha, True)
    out = np.zeros(len(wi))
    for k, w in enumerate(wi):
        for v in (w, w * np.array([1.0, 1.0, -1.0])):
            s = wo + v
            h = s / np.linalg.norm(s)
            if h[2] > 0:
                out[k] += d.pdf(mi.Vector3f(*wo), mi.Vector3f(*h)) / (4.0 * np.dot(wo, h))
    return out


CASES = [(dist, model, alpha, deg)
         for dist, model in (("GGX", "ggx_sep"), ("Beckmann", "beckmann"))
         for alpha in (0.05, 0.3, 0.8)
         for deg in (0.0, 30.0, 60.0, 80.0, 87.0)]


@pytest.mark.parametrize("dist,model,alpha,deg", CASES, ids=[f"{c[1]}-a{c[2]}-{c[3]:g}deg" for c in CASES])
def test_visible_normal_pdf_matches_mitsuba(cli, tmp_path, dist, model, alpha, deg):
    t = np.radians(deg)
    wo = np.array([np.sin(t) * np.cos(0.4), np.sin(t) * np.sin(0.4), np.cos(t)])
    params = {f"{model}.ks_{c}": 1.0 for c in "rgb"}
    params[f"{model}.alpha"] = alpha
    params[f"{model}.f0"] = 0.5
    wi, ours = brdfz_samples(cli, tmp_path, model, params, wo)
    ok = ours > 0
    assert ok.mean() > 0.99  # failed draws are rare
    theirs = mitsuba_pdf(dist, alpha, wo, wi[ok])
    tol = 1e-4 if dist == "GGX" else 5e-3
    rel = np.abs(ours[ok] - theirs) / theirs
    k = int(np.argmax(rel))
    assert rel[k] < tol, f"wi={wi[ok][k]}: brdfz {ours[ok][k]}, mitsuba {theirs[k]}"
