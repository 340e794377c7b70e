"""`brdfz convert` between every readable and writable format, `brdfz validate`, and `brdfz info` on
.brdfz containers: the command's behaviour, including one-line errors and no output file on bad input."""

import hashlib
import json
import os
import signal
import struct
import subprocess
import time

import numpy as np
import pytest

from conftest import run

TABLE_FORMATS = [".binary", ".brdfz", ".exr"]  # hold a table exactly
ALL_FORMATS = TABLE_FORMATS + [".bsdf"]

MODEL_JSON = {
    "format": "brdfz-analytic",
    "version": 1,
    "model": "lambert+ggx",
    "parameters": {
        "lambert.rho_r": 0.2, "lambert.rho_g": 0.3, "lambert.rho_b": 0.4,
        "ggx.ks_r": 1, "ggx.ks_g": 1, "ggx.ks_b": 1, "ggx.alpha": 0.2, "ggx.f0": 0.04,
    },
}


def leftovers(folder):
    return [p.name for p in folder.iterdir() if ".tmp-" in p.name]


@pytest.fixture(scope="module")
def sources(cli, demo_table, tmp_path_factory):
    """The demo table in every format brdfz writes."""
    d = tmp_path_factory.mktemp("sources")
    out = {}
    for ext in ALL_FORMATS:
        out[ext] = d / f"demo{ext}"
        run(cli, "convert", demo_table, out[ext])
    return out


@pytest.mark.parametrize("src_ext", ALL_FORMATS)
@pytest.mark.parametrize("dst_ext", ALL_FORMATS)
def test_convert_every_pair(cli, sources, tmp_path, src_ext, dst_ext):
    dst = tmp_path / f"out{dst_ext}"
    proc = run(cli, "convert", sources[src_ext], dst)
    assert proc.stdout.startswith(f"wrote {dst}")
    assert dst.exists() and not leftovers(tmp_path)
    run(cli, "info", dst)


def test_table_formats_are_lossless(cli, demo_table, tmp_path):
    """MERL -> .brdfz -> .exr -> .brdfz -> MERL gives back the same bytes."""
    chain = [demo_table, tmp_path / "a.brdfz", tmp_path / "b.exr", tmp_path / "c.brdfz", tmp_path / "d.binary"]
    for src, dst in zip(chain, chain[1:]):
        run(cli, "convert", src, dst)
    assert (tmp_path / "d.binary").read_bytes() == demo_table.read_bytes()


def test_from_to_override_extensions(cli, demo_table, tmp_path):
    src = tmp_path / "table.data"
    src.write_bytes(demo_table.read_bytes())
    out = tmp_path / "table.out"
    run(cli, "convert", src, out, "--from", "merl", "--to", "brdfz")
    back = tmp_path / "back.binary"
    run(cli, "convert", out, back, "--from", "brdfz")
    assert back.read_bytes() == demo_table.read_bytes()


def test_analytic_models_round_trip(cli, tmp_path):
    src = tmp_path / "model.json"
    src.write_text(json.dumps(MODEL_JSON))
    run(cli, "convert", src, tmp_path / "model.brdfz")
    info = json.loads(run(cli, "info", tmp_path / "model.brdfz", "--json").stdout)
    assert info["container"]["representation"] == "analytic"
    assert info["container"]["achieved"]["lossless"] is True
    run(cli, "convert", tmp_path / "model.brdfz", tmp_path / "back.json")
    assert json.loads((tmp_path / "back.json").read_text())["parameters"] == MODEL_JSON["parameters"]


def test_info_shows_container_metadata(cli, demo_table, tmp_path):
    out = tmp_path / "t.brdfz"
    run(cli, "convert", demo_table, out)
    info = json.loads(run(cli, "info", out, "--json").stdout)
    c = info["container"]
    assert c["source"] == {
        "file": demo_table.name,
        "format": "merl",
        "sha256": hashlib.sha256(demo_table.read_bytes()).hexdigest(),
    }
    # Written by a version-9 writer; a float32 table needs only version-1 features.
    assert c["version"] == 9 and c["min_reader_version"] == 1
    assert "tabular" in [f.split("@")[0] for f in c["features"]]
    assert c["units"] == "1/sr" and c["cosine"] == "excluded"
    assert c["datasets"][0]["path"] == "/representation/values"
    text = run(cli, "info", out).stdout
    assert "container  version 9 (readers >= 1)" in text and "sha256" in text and "dataset    /representation/values" in text


@pytest.mark.parametrize("ext", ALL_FORMATS + [".json"])
def test_bad_input_one_line_no_output(cli, tmp_path, ext):
    """Garbage, and a truncated valid file, in every readable format."""
    bad = tmp_path / f"bad{ext}"
    for content in (b"not a brdf file at all\n" * 3, b""):
        bad.write_bytes(content)
        out = tmp_path / "out.brdfz"
        proc = run(cli, "convert", bad, out, check=False)
        assert proc.returncode != 0
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"brdfz: {bad}"), proc.stderr
        assert not out.exists() and not leftovers(tmp_path)


def test_truncated_files_are_refused(cli, sources, tmp_path):
    for ext, src in sources.items():
        data = src.read_bytes()
        bad = tmp_path / f"cut{ext}"
        bad.write_bytes(data[: len(data) // 2])
        out = tmp_path / "out.binary"
        proc = run(cli, "convert", bad, out, check=False)
        assert proc.returncode != 0 and len(proc.stderr.strip().splitlines()) == 1, (ext, proc.stderr)
        assert not out.exists() and not leftovers(tmp_path)


def test_killed_write_leaves_no_file(cli, sources, tmp_path):
    out = tmp_path / "big.brdfz"
    proc = subprocess.Popen([cli, "convert", str(sources[".bsdf"]), str(out), "--res", "180x180x360"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.5)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not out.exists()


def test_validate_passes_a_plausible_table(cli, demo_table):
    proc = run(cli, "validate", demo_table)
    assert "non-negativity  ok" in proc.stdout
    assert "reciprocity     ok" in proc.stdout
    assert "energy          ok" in proc.stdout


def test_validate_reports_energy_violations(cli, demo_table, tmp_path):
    """The demo table scaled by 4 reflects more than it receives."""
    data = demo_table.read_bytes()
    dims = struct.unpack("<3i", data[:12])
    values = np.frombuffer(data[12:], dtype="<f8").copy()
    values[values > 0] *= 4.0
    hot = tmp_path / "hot.binary"
    hot.write_bytes(struct.pack("<3i", *dims) + values.astype("<f8").tobytes())
    proc = run(cli, "validate", hot, check=False)
    assert proc.returncode == 1
    assert "energy          FAIL" in proc.stdout and "theta" in proc.stdout
    assert proc.stderr.strip() == f"brdfz: {hot}: validation failed: energy"
    report = json.loads(run(cli, "validate", hot, "--json", check=False).stdout)
    assert report["ok"] is False and report["energy"]["failed"] > 0
    assert all(w["albedo_viewed"][0] > 1.0 or w["reflectance_lit"][0] > 1.0 for w in report["energy"]["worst"])


def tensor_fields(data):
    """name -> (dtype code, offset, shape) of a tensor_file."""
    count = struct.unpack_from("<I", data, 14)[0]
    pos, fields = 18, {}
    for _ in range(count):
        n = struct.unpack_from("<H", data, pos)[0]
        name = data[pos + 2 : pos + 2 + n].decode()
        pos += 2 + n
        rank, dtype, offset = struct.unpack_from("<HBQ", data, pos)
        pos += 11
        shape = struct.unpack_from(f"<{rank}Q", data, pos)
        pos += 8 * rank
        fields[name] = (dtype, offset, shape)
    return fields


def test_validate_reports_negative_values_and_reciprocity(cli, sources, tmp_path):
    """An RGL file whose red values are negated: negative f, reported with its directions."""
    data = bytearray(sources[".bsdf"].read_bytes())
    _, offset, shape = tensor_fields(bytes(data))["rgb"]
    rgb = np.frombuffer(bytes(data), dtype="<f4", count=int(np.prod(shape)), offset=offset).reshape(shape).copy()
    rgb[:, :, 0] *= -1.0
    data[offset : offset + rgb.nbytes] = rgb.astype("<f4").tobytes()
    neg = tmp_path / "neg.bsdf"
    neg.write_bytes(bytes(data))
    proc = run(cli, "validate", neg, "--res", "30x30x60", check=False)
    assert proc.returncode == 1
    assert "non-negativity  FAIL" in proc.stdout
    assert "validation failed: non-negativity" in proc.stderr


def test_validate_real_rgl_data(cli, rgl_files):
    """Real measurements are not exactly reciprocal; validate says so and where, without failing to run."""
    proc = run(cli, "validate", rgl_files[0], "--json", check=False)
    report = json.loads(proc.stdout)
    assert proc.returncode == (0 if report["ok"] else 1)
    for check in ("non-negativity", "reciprocity", "energy"):
        assert report[check]["tested"] > 0
