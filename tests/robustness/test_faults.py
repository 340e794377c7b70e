"""The fault sweep on the command: writes killed with SIGKILL or SIGTERM, a full disk (a file size
limit), the umask and a replaced file's mode, reproducible .brdfz bytes."""
import csv
import os
import re
import resource
import signal
import stat
import subprocess
import time

import pytest

from conftest import run

FORMATS = [".brdfz", ".binary", ".exr", ".bsdf", ".npy"]


def temporaries(folder):
    return sorted(p.name for p in folder.iterdir() if ".tmp-" in p.name)


def signal_mid_write(cmd, sig, after_bytes=64 << 10):
    """Runs cmd and sends sig once it has written after_bytes (its write counter in /proc), so the
    signal lands while the output is being written; returns the exit status."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while proc.poll() is None:
        try:
            with open(f"/proc/{proc.pid}/io") as f:
                written = int(re.search(r"^wchar: (\d+)", f.read(), re.M).group(1))
        except (OSError, AttributeError):
            break
        if written > after_bytes:
            proc.send_signal(sig)
            break
        time.sleep(0.001)
    return proc.wait(timeout=300)


# The killed-process tests are heavy: a killed process cannot report a sanitizer finding, so the
# sanitizer tree leaves them to the Release run (files_test.cpp kills the writer itself there).
@pytest.mark.heavy
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
@pytest.mark.parametrize("ext", FORMATS)
def test_killed_writes_leave_no_file_and_no_temporary(cli, demo_table, tmp_path, monkeypatch, ext, sig):
    """Signalled while writing (and, earlier, while still tabulating): nothing is left at OUT nor
    beside it, and an OUT that was there before is unchanged. A signal that lands after the file
    is linked in (the process had not exited yet) leaves the whole file, never a part."""
    if not os.path.exists(f"/proc/{os.getpid()}/io"):
        pytest.skip("no /proc/PID/io to see when the output is being written")
    out = tmp_path / f"OUT{ext}"
    cmd = [cli, "convert", str(demo_table), str(out), "--res", "90x90x360"]
    reference = tmp_path / "whole" / out.name
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")  # so a whole .brdfz is the reference's bytes

    def whole():
        if not reference.exists():
            reference.parent.mkdir()
            run(cli, "convert", demo_table, reference, "--res", "90x90x360")
        return reference.read_bytes()

    def left_nothing(status):
        """No temporary; no OUT and the signal's status, or the whole OUT (then removed)."""
        assert temporaries(tmp_path) == [], ext
        if not out.exists():
            assert status == -sig, (ext, status)
            return True
        assert out.read_bytes() == whole(), (ext, status)
        out.unlink()
        return False

    # Until one signal lands mid-write.
    if not any(left_nothing(signal_mid_write(cmd, sig)) for _ in range(3)):
        pytest.fail("never signalled mid-write")
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.3)  # while tabulating, unless it is done already
    proc.send_signal(sig)
    left_nothing(proc.wait(timeout=300))
    run(cli, "convert", demo_table, out)
    before = out.read_bytes()
    signal_mid_write(cmd, sig, after_bytes=(64 << 10) + len(before))
    assert temporaries(tmp_path) == []
    after = out.read_bytes()
    assert after == before or after == whole()


def limited(max_bytes):
    def setup():
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_bytes, max_bytes))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG, as on a full disk
    return setup


@pytest.mark.parametrize("ext", FORMATS)
def test_a_full_disk_is_one_line_and_no_file(cli, demo_table, tmp_path, ext):
    out = tmp_path / f"full{ext}"
    proc = subprocess.run([cli, "convert", str(demo_table), str(out)], capture_output=True, text=True,
                          preexec_fn=limited(1 << 20), timeout=300)
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"brdfz: {out}: ") and "HDF5-DIAG" not in proc.stderr
    assert not out.exists() and temporaries(tmp_path) == []


def test_new_files_follow_the_umask_and_replaced_ones_keep_their_mode(cli, demo_table, tmp_path):
    model = tmp_path / "lambert.json"  # the analytic model writer, from a model
    model.write_text('{"format": "brdfz-analytic", "version": 1, "model": "lambert", "parameters": '
                     '{"lambert.rho_r": 0.3, "lambert.rho_g": 0.4, "lambert.rho_b": 0.5}}')
    for ext, src in [(ext, demo_table) for ext in FORMATS] + [(".json", model)]:
        out = tmp_path / f"m{ext}"
        subprocess.run([cli, "convert", str(src), str(out), "--res", "8x8x16"], check=True,
                       capture_output=True, preexec_fn=lambda: os.umask(0o027))
        assert stat.S_IMODE(out.stat().st_mode) == 0o640, ext
        out.chmod(0o600)
        run(cli, "convert", src, out, "--res", "8x8x16")
        assert stat.S_IMODE(out.stat().st_mode) == 0o600, ext


def test_brdfz_bytes_are_reproducible_with_source_date_epoch(cli, demo_table, tmp_path):
    env = dict(os.environ, SOURCE_DATE_EPOCH="1700000000")
    outs = [tmp_path / "a.brdfz", tmp_path / "b.brdfz"]
    for k, out in enumerate(outs):
        if k:
            time.sleep(1.1)  # object times, were they stored, would differ
        subprocess.run([cli, "compress", str(demo_table), "-o", str(out), "--repr", "svd:rank=1,res=16x16x32"],
                       check=True, capture_output=True, env=env)
    assert outs[0].read_bytes() == outs[1].read_bytes()
    assert "2023-11-14T22:13:20Z" in run(cli, "info", outs[0]).stdout
    bad = subprocess.run([cli, "convert", str(demo_table), str(tmp_path / "c.brdfz")], capture_output=True, text=True,
                         env=dict(os.environ, SOURCE_DATE_EPOCH="yesterday"))
    assert bad.returncode == 1 and "SOURCE_DATE_EPOCH='yesterday'" in bad.stderr
    assert not (tmp_path / "c.brdfz").exists()


@pytest.mark.heavy
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_killed_demo_leaves_no_partial_csv(cli, tmp_path, sig):
    """demo writes representations.csv whole once every setting is measured: signalled while it
    builds them, it leaves neither the CSV nor a temporary; left alone, the CSV has a row a setting."""
    specs = ["analytic:lambert+ggx", "tabular:res=32x32x64", "svd:rank=2,space=log,res=32x32x32"]
    cmd = [cli, "demo", "--out", str(tmp_path)] + [a for s in specs for a in ("--repr", s)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for line in proc.stdout:
        if line.lstrip().startswith("tabular:res=32x32x64"):  # the first settings are measured
            proc.send_signal(sig)
            break
    proc.stdout.close()
    assert proc.wait(timeout=300) == -sig
    assert not (tmp_path / "representations.csv").exists() and temporaries(tmp_path) == []
    run(cli, *cmd[1:])
    with open(tmp_path / "representations.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["repr"] for r in rows] == specs and all(r["status"].startswith("ok") for r in rows)
