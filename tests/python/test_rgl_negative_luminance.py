"""A real RGL-EPFL file whose `luminance` tensor holds slightly negative values (as noisy measurements
do where the density is ~0) loads in brdfz as in Mitsuba 3's `measured`, the reference reader, and
`brdfz info` reports how many values were out of range (rgl.h, ReadResult::luminance_negative)."""

import json
import os
import pathlib
import struct
import subprocess

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

REPO = pathlib.Path(__file__).resolve().parents[2]
RGL_FILE = REPO.parent / "shared" / "data" / "rgl" / "satin_rosaline_rgb.bsdf"
MAGIC = b"tensor_file\0"


def field_offsets(data):
    """{name: (byte offset, element count)} of a Mitsuba tensor file's float32 fields."""
    assert data[:12] == MAGIC
    (count,) = struct.unpack_from("<I", data, 14)
    pos, out = 18, {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", data, pos)
        name = data[pos + 2:pos + 2 + n].decode()
        pos += 2 + n
        ndim, dtype, offset = struct.unpack_from("<HBQ", data, pos)
        pos += 11
        shape = struct.unpack_from(f"<{ndim}Q", data, pos)
        pos += 8 * ndim
        out[name] = (offset, int(np.prod(shape)), dtype)
    return out


@pytest.fixture(scope="module")
def noisy(tmp_path_factory):
    """satin_rosaline with its 200 smallest luminance values set to -1e-6 of the largest."""
    if not RGL_FILE.exists():
        pytest.skip(f"{RGL_FILE} is missing")
    data = bytearray(RGL_FILE.read_bytes())
    offset, n, _ = field_offsets(data)["luminance"]
    lum = np.frombuffer(data, dtype="<f4", count=n, offset=offset).copy()
    assert (lum >= 0).all()  # the file as published: the negatives below are the test's
    picked = np.argsort(lum)[:200]
    lum[picked] = -1e-6 * lum.max()
    data[offset:offset + 4 * n] = lum.astype("<f4").tobytes()
    path = tmp_path_factory.mktemp("rgl") / "satin_rosaline_noisy.bsdf"
    path.write_bytes(bytes(data))
    return path, len(picked)


def test_mitsuba_reads_the_file(noisy):
    path, _ = noisy
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.1, 0.95)
    bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.5, mi.Point2f(0.3, 0.7))
    assert np.isfinite(np.array(weight)).all()


def test_brdfz_loads_it_and_counts_the_negatives(noisy):
    cli = os.environ.get("BRDFZ_CLI")
    if not cli:
        pytest.skip("BRDFZ_CLI is not set (path of the brdfz command)")
    path, count = noisy
    info = json.loads(subprocess.run([cli, "info", str(path), "--json"], check=True, capture_output=True,
                                     text=True).stdout)
    assert info["luminance_negative"] == count
    text = subprocess.run([cli, "info", str(path)], check=True, capture_output=True, text=True).stdout
    assert f"luminance  {count} negative values" in text
    original = json.loads(subprocess.run([cli, "info", str(RGL_FILE), "--json"], check=True, capture_output=True,
                                         text=True).stdout)
    assert original["luminance_negative"] == 0
    assert info["negative"] == original["negative"]  # the rgb tensor's count is unchanged


def test_brdfz_samples_it_with_finite_pdfs(noisy):
    cli = os.environ.get("BRDFZ_CLI")
    if not cli:
        pytest.skip("BRDFZ_CLI is not set (path of the brdfz command)")
    path, _ = noisy
    run = subprocess.run([cli, "sample", str(path), "--wo", "0.3,0.1,0.9487", "-n", "4000", "--seed", "3"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    rows = np.loadtxt(run.stdout.splitlines()[1:], delimiter=",").reshape(-1, 7)
    assert np.isfinite(rows).all()
    assert (rows[:, 3] >= 0).all() and (rows[:, 3] > 0).mean() > 0.9
