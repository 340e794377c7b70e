"""Anisotropic RGL `.bsdf` files (phi_i with several entries) written by brdfz, read by Mitsuba 3's `measured`
plugin (scalar_rgb) as the independent reader.

A `lambert+ggx_aniso` model (αx = 0.15, αy = 0.4) is converted with `brdfz convert MODEL.json OUT.bsdf --phi-i 25`.
On 5,000 seeded random direction pairs (float32-representable):

1. Mitsuba and brdfz evaluate the file alike: per channel |ours·cosθo − mitsuba| ≤ max(1e-3·|mitsuba|, 1e-5),
   the tolerance of the isotropic cross-checks; and directions brdfz samples have Mitsuba's pdf to 1e-3
   (1e-2 within 1e-3 rad of the normal, as in test_rgl_mitsuba.py).
2. The file reproduces its source (cosine-weighted relative RMSE over θi, θo < 80° below REL_RMSE).
3. Files whose φi entries cover half or a quarter of the circle (Mitsuba's symmetry reductions; made here by
   keeping the first 13 or 7 of the 25 slices) are folded alike by both readers.
"""

import json
import struct

import numpy as np
import pytest

from conftest import run
from test_rgl_mitsuba import brdfz_sample, view
from test_rgl_mitsuba import mitsuba_pdf as sampler_pdf
from test_rgl_write_mitsuba import brdfz_eval, mitsuba_bsdf, mitsuba_eval, random_upper

mi = pytest.importorskip("mitsuba")

N_PAIRS = 5_000
REL_TOL, ABS_TOL = 1e-3, 1e-5
# Measured here (25 φi x 24 θi slices, 64x64 rgb): 0.024; the limit leaves room.
REL_RMSE = 0.05
MODEL = {
    "format": "brdfz-analytic",
    "version": 1,
    "model": "lambert+ggx_aniso",
    "parameters": {
        "lambert.rho_r": 0.3, "lambert.rho_g": 0.2, "lambert.rho_b": 0.1,
        "ggx_aniso.ks_r": 1, "ggx_aniso.ks_g": 1, "ggx_aniso.ks_b": 1,
        "ggx_aniso.alpha_x": 0.15, "ggx_aniso.alpha_y": 0.4, "ggx_aniso.f0": 0.5,
    },
}
DTYPE_SIZE = {1: 1, 10: 4}  # u8, f32: the dtypes RGL files use


def read_tensor_file(path):
    """{name: (dtype code, shape, raw bytes)} of a tensor_file."""
    b = pathlib_bytes(path)
    assert b[:12] == b"tensor_file\0"
    (count,) = struct.unpack_from("<I", b, 14)
    pos, fields = 18, {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", b, pos)
        name = b[pos + 2 : pos + 2 + n].decode()
        pos += 2 + n
        ndim, dtype, offset = struct.unpack_from("<HBQ", b, pos)
        pos += 11
        shape = struct.unpack_from(f"<{ndim}Q", b, pos)
        pos += 8 * ndim
        size = int(np.prod(shape)) * DTYPE_SIZE[dtype]
        fields[name] = (dtype, shape, b[offset : offset + size])
    return fields


def write_tensor_file(path, fields):
    header = bytearray(b"tensor_file\0" + bytes([1, 0]) + struct.pack("<I", len(fields)))
    size = len(header) + sum(2 + len(k) + 2 + 1 + 8 + 8 * len(v[1]) for k, v in fields.items())
    offsets = []
    for _, (_, _, data) in fields.items():
        size = (size + 7) // 8 * 8
        offsets.append(size)
        size += len(data)
    for (name, (dtype, shape, _)), off in zip(fields.items(), offsets):
        header += struct.pack("<H", len(name)) + name.encode() + struct.pack("<HBQ", len(shape), dtype, off)
        header += struct.pack(f"<{len(shape)}Q", *shape)
    out = bytearray(header)
    for (_, (_, _, data)), off in zip(fields.items(), offsets):
        out += bytes(off - len(out)) + data
    with open(path, "wb") as f:
        f.write(out)


def pathlib_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def first_phi_slices(src, dst, keep):
    """A copy of an anisotropic file with only its first `keep` φi slices."""
    fields = read_tensor_file(src)
    for name in ("phi_i", "vndf", "luminance", "rgb"):
        dtype, shape, data = fields[name]
        per = len(data) // shape[0]
        fields[name] = (dtype, (keep,) + tuple(shape[1:]), data[: keep * per])
    write_tensor_file(dst, fields)


def check_readers_agree(cli, path, wi, wo, tmp_path):
    ref = mitsuba_eval(mitsuba_bsdf(path), wi, wo)
    ours = brdfz_eval(cli, path, wi, wo, tmp_path)
    assert np.isfinite(ref).all() and np.isfinite(ours).all()
    err = np.abs(ours * wo[:, 2:3] - ref)
    bad = err > np.maximum(REL_TOL * np.abs(ref), ABS_TOL)
    assert not bad.any(), f"{path.name}: {bad.any(axis=1).sum()} pairs differ between Mitsuba and brdfz (max {err.max():.3g})"
    return ref


@pytest.fixture(scope="module")
def written(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("aniso")
    model = d / "brushed.json"
    model.write_text(json.dumps(MODEL))
    path = d / "brushed.bsdf"
    run(cli, "convert", model, path, "--phi-i", 25)
    return model, path


def pairs(seed):
    rng = np.random.default_rng(seed)
    wi = random_upper(rng, N_PAIRS).astype(np.float32).astype(np.float64)
    wo = random_upper(rng, N_PAIRS).astype(np.float32).astype(np.float64)
    return wi, wo


def test_anisotropic_bsdf_evaluates_in_mitsuba_as_in_brdfz(cli, written, tmp_path):
    model, path = written
    assert read_tensor_file(path)["phi_i"][1] == (25,)
    wi, wo = pairs(20181204)
    ref = check_readers_agree(cli, path, wi, wo, tmp_path)

    # The file reproduces its (anisotropic) source.
    source = brdfz_eval(cli, model, wi, wo, tmp_path)
    cos_i, cos_o = wi[:, 2:3], wo[:, 2:3]
    keep = ((cos_i > np.cos(np.radians(80))) & (cos_o > np.cos(np.radians(80))))[:, 0]
    x, y = (source * cos_i)[keep], (ref / cos_o * cos_i)[keep]
    rel_rmse = np.sqrt(((x - y) ** 2).sum() / (x**2).sum())
    print(f"anisotropic file vs its source: cosine-weighted relative RMSE {rel_rmse:.4f} (limit {REL_RMSE})")
    assert rel_rmse <= REL_RMSE



def test_anisotropic_bsdf_samples_with_mitsuba_pdf(cli, written):
    # brdfz's pdf(wo = A, wi = B) is Mitsuba's pdf(si.wi = A, wo = B) (rgl.h), at azimuths of both signs.
    _, path = written
    for deg, phi in ((30.0, 0.4), (60.0, 2.0), (45.0, -2.5)):
        wo = view(deg, phi)
        rows = brdfz_sample(cli, path, wo, 2000, seed=int(deg))
        drawn = rows[:, 3] > 0
        assert drawn.mean() > 0.9
        wi, pdf = rows[drawn, :3], rows[drawn, 3]
        ref = sampler_pdf(path, wo, wi)
        m = wi + wo
        m /= np.linalg.norm(m, axis=1)[:, None]
        theta_m = 2 * np.arcsin(0.5 * np.linalg.norm(m - [0.0, 0.0, 1.0], axis=1))
        rel = np.abs(pdf - ref) / ref
        tol = np.where(theta_m < 1e-3, 1e-2, 1e-3)  # as test_rgl_mitsuba.py: ill-conditioned near the normal
        assert (rel <= tol).all(), f"view {deg} deg, phi {phi}: {(rel > tol).sum()} pdfs differ (max {rel.max():.3g})"


def test_half_and_quarter_phi_ranges_fold_alike(cli, written, tmp_path):
    _, path = written
    wi, wo = pairs(7)
    for keep, name in ((13, "half"), (7, "quarter")):
        folded = tmp_path / f"{name}.bsdf"
        first_phi_slices(path, folded, keep)
        check_readers_agree(cli, folded, wi, wo, tmp_path)
