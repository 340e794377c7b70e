"""RGL fields out of range, decided with Mitsuba 3's `measured` plugin as the reference for what can be
rendered: a file it renders loads (slightly negative luminance, counted per field); one where it would
return NaN, Inf or negative reflectance everywhere the field is read is refused, naming the field,
and validate fails."""
import json
import struct

import numpy as np
import pytest

from conftest import run

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is the reference for what renders")


def fields(data):
    """name -> (offset, shape) of a tensor_file's fields."""
    count = struct.unpack_from("<I", data, 14)[0]
    pos, out = 18, {}
    for _ in range(count):
        n = struct.unpack_from("<H", data, pos)[0]
        name = data[pos + 2 : pos + 2 + n].decode()
        pos += 2 + n
        rank, _, offset = struct.unpack_from("<HBQ", data, pos)
        pos += 11
        out[name] = (offset, struct.unpack_from(f"<{rank}Q", data, pos))
        pos += 8 * rank
    return out


def edited(base, out, name, change):
    data = bytearray(base.read_bytes())
    offset, shape = fields(bytes(data))[name]
    values = np.frombuffer(bytes(data), dtype="<f4", count=int(np.prod(shape)), offset=offset).copy()
    values = np.asarray(change(values), dtype="<f4")
    data[offset : offset + values.nbytes] = values.tobytes()
    out.write_bytes(bytes(data))
    return out


@pytest.fixture(scope="module")
def base(cli, demo_table, tmp_path_factory):
    path = tmp_path_factory.mktemp("rgl") / "base.bsdf"
    run(cli, "convert", demo_table, path)
    return path


def mitsuba_values(path, n=300):
    """Mitsuba's eval (f·cosθo) at n random pairs above the horizon."""
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    rng = np.random.default_rng(7)
    ctx, si, out = mi.BSDFContext(), mi.SurfaceInteraction3f(), []
    for _ in range(n):
        a, b = (mi.warp.square_to_cosine_hemisphere(mi.Point2f(*rng.random(2))) for _ in range(2))
        si.wi = a
        v = bsdf.eval(ctx, si, b)
        out.append((v[0], v[1], v[2]))
    return np.array(out)


REFUSED = {
    "rgb all NaN": ("rgb", lambda v: np.full_like(v, np.nan), "field 'rgb' has no finite value >= 0"),
    "rgb all Inf": ("rgb", lambda v: np.full_like(v, np.inf), "field 'rgb' has no finite value >= 0"),
    "ndf negative": ("ndf", lambda v: -v - 1e-3, "field 'ndf' holds"),
    "sigma negative": ("sigma", lambda v: -v, "field 'sigma' holds"),
    "sigma zero": ("sigma", lambda v: 0 * v, "field 'sigma' holds"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_fields_mitsuba_cannot_render_are_refused_and_fail_validate(cli, base, tmp_path, case):
    name, change, message = REFUSED[case]
    bad = edited(base, tmp_path / "bad.bsdf", name, change)
    # The reference: Mitsuba loads it, but returns no finite non-negative reflectance.
    ref = mitsuba_values(bad)
    assert not np.any(np.isfinite(ref) & (ref > 0)) or np.any(ref < 0), case
    for command in (["info", bad], ["validate", bad], ["convert", bad, tmp_path / "out.brdfz"]):
        proc = run(cli, *command, check=False)
        assert proc.returncode == 1, (case, command)
        assert message in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out.brdfz").exists()


def test_slightly_negative_luminance_loads_and_is_counted(cli, base, tmp_path):
    """Real files hold it; Mitsuba renders them: loaded, counted per field, sampled."""
    noisy = edited(base, tmp_path / "noisy.bsdf", "luminance",
                   lambda v: np.where(np.arange(v.size) % 97 == 0, -1e-3, v))
    negatives = int((np.arange(int(np.prod(fields(noisy.read_bytes())["luminance"][1]))) % 97 == 0).sum())
    ref = mitsuba_values(noisy)
    assert np.isfinite(ref).all() and (ref >= 0).all()
    info = run(cli, "info", noisy).stdout
    assert f"field      luminance: {negatives} negative, 0 NaN, 0 Inf" in info
    report = json.loads(run(cli, "info", noisy, "--json").stdout)
    assert report["fields"]["luminance"]["negative"] == negatives
    assert report["fields"]["ndf"]["negative"] == 0
    rows = run(cli, "sample", noisy, "--wo", "0.2,0.1,0.97", "-n", "500").stdout.splitlines()[1:]
    pdfs = np.array([float(r.split(",")[3]) for r in rows])
    assert np.isfinite(pdfs).all() and (pdfs >= 0).all() and (pdfs > 0).mean() > 0.9
    # Converted, the file keeps its values (the container stores the tensors as read).
    run(cli, "convert", noisy, tmp_path / "noisy.brdfz")
    run(cli, "convert", tmp_path / "noisy.brdfz", tmp_path / "again.bsdf")
    again = tmp_path / "again.bsdf"
    offset, shape = fields(again.read_bytes())["luminance"]
    lum = np.frombuffer(again.read_bytes(), dtype="<f4", count=int(np.prod(shape)), offset=offset)
    assert int((lum < 0).sum()) == negatives
