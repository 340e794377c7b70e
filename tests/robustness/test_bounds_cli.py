"""Bounds on the command: resolutions that would wrap a 32-bit int, --threads, seeds and spec values
out of range (said so, not "not an integer"), φh slices beyond what a .brdfz file holds, Ceres' log
lines kept out of fit's output, and eval --pairs in bounded memory."""
import os
import subprocess
import sys

import pytest

from conftest import run

LAMBERT = ('{"format": "brdfz-analytic", "version": 1, "model": "lambert", "parameters": '
           '{"lambert.rho_r": 0.3, "lambert.rho_g": 0.4, "lambert.rho_b": 0.5}}')


def one_error_line(proc):
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    return lines[0]


@pytest.fixture
def lambert(tmp_path):
    path = tmp_path / "lambert.json"
    path.write_text(LAMBERT)
    return path


# Every command that takes --res with the case that wrapped; convert with the rest.
@pytest.mark.parametrize("command, res", [
    *[(["convert", "{in}", "{out}.binary"], res)
      for res in ["4294967298x4294967300x1", "8x8x4294967312", "8x-8x16", "8x8x16x", " 8x8x16"]],
    (["validate", "{in}"], "4294967298x4294967300x1"),
    (["pca-train", "{in}", "{in}", "-o", "{out}.brdfz"], "4294967298x4294967300x1"),
])
def test_a_resolution_that_wraps_or_is_not_digits_is_refused(cli, small_table, tmp_path, command, res):
    args = [a.format(**{"in": small_table, "out": tmp_path / "x"}) for a in command]
    proc = run(cli, *args, "--res", res, check=False)
    assert proc.returncode == 1, proc.stdout
    line = one_error_line(proc)
    assert line.startswith(f"brdfz: resolution '{res}'"), line
    assert not any(tmp_path.iterdir())


COMPRESS = ["compress", "{in}", "-o", "{out}.brdfz", "--repr", "tabular:res=4x4x8"]


@pytest.mark.parametrize("command, threads", [
    *[(COMPRESS, threads) for threads in ["1000000000", "99999999999999999999", "1025"]],
    (["fit", "{in}", "--model", "lambert", "-o", "{out}.json"], "1000000000"),
    (["pca-train", "{in}", "{in}", "-o", "{out}.brdfz"], "1000000000"),
])
def test_threads_beyond_the_limit_are_one_line_before_any_work(cli, small_table, tmp_path, command, threads):
    args = [a.format(**{"in": small_table, "out": tmp_path / "x"}) for a in command]
    proc = run(cli, *args, "--threads", threads, check=False)
    assert proc.returncode == 1
    assert one_error_line(proc) == f"brdfz: --threads: {threads} is above the limit of 1024 threads (brdfz --help)"
    assert not any(tmp_path.iterdir())


def test_fit_prints_no_solver_log_lines_with_more_threads_than_cores(cli, small_table, tmp_path):
    """More threads than cores (within the limit): Ceres would log that it bounds them, through glog."""
    proc = run(cli, "fit", small_table, "--model", "lambert", "-o", tmp_path / "m.json", "--threads", "1024",
               "--starts", "2", "--samples", "2000")
    assert "InitGoogleLogging" not in proc.stderr and "num_threads" not in proc.stderr, proc.stderr
    assert proc.stderr == ""


@pytest.mark.parametrize("seed", ["-1", "18446744073709551616", "99999999999999999999999"])
def test_seeds_out_of_range_say_so(cli, small_table, seed):
    for args in (["sample", small_table, "--wo", "0,0,1", "-n", "1"],
                 ["diff", small_table, small_table, "--over", "directions", "--directions", "16"]):
        proc = run(cli, *args, f"--seed={seed}", check=False)
        assert proc.returncode == 1 and proc.stdout == ""
        assert f"'{seed}' is outside [0, 18446744073709551615]" in one_error_line(proc)
    proc = run(cli, "sample", small_table, "--wo", "0,0,1", "-n", "1", "--seed=1e3", check=False)
    assert "'1e3' is not an integer in [0, 18446744073709551615]" in one_error_line(proc)


@pytest.mark.parametrize("spec, message", [
    ("svd:iterations=4000000000", "svd: iterations=4000000000 is outside [1, 100000]"),
    ("analytic:lambert,seed=99999999999", "analytic: seed=99999999999 is outside [0, 1073741824]"),
    ("tabular:res=4x4x8,phih=255", "tabular: phih=255 is outside [1, 249]"),
    ("tabular:res=4x4x8,phih=1200", "tabular: phih=1200 is outside [1, 249]"),
    ("nmf:rank=1,res=4x4x8,phih=84", "nmf: phih=84 is outside [1, 83]"),
])
def test_spec_values_out_of_range_are_refused_before_any_build(cli, small_table, tmp_path, spec, message):
    out = tmp_path / "x.brdfz"
    proc = run(cli, "compress", small_table, "-o", out, "--repr", spec, check=False)
    assert proc.returncode == 1
    assert one_error_line(proc) == f"brdfz: {message}"
    assert not out.exists()


def rss_mb(args, stdin_rows=0):
    """Runs the command (stdout discarded; `stdin_rows` pairs fed through a pipe) and returns
    (exit status, its peak RSS in MB, stderr)."""
    code = ("import resource, subprocess, sys, threading\n"
            "rows, args = int(sys.argv[1]), sys.argv[2:]\n"
            "p = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)\n"
            "def feed():\n"
            "    block = b'0,0,1,0.1,0.2,0.97\\n' * 100000\n"
            "    for _ in range(rows // 100000):\n"
            "        p.stdin.write(block)\n"
            "    p.stdin.close()\n"
            "threading.Thread(target=feed, daemon=True).start()\n"
            "err = p.stderr.read()\n"
            "print(p.wait(), resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss // 1024)\n"
            "sys.stderr.write(err.decode())\n")
    # Under AddressSanitizer freed memory waits in a quarantine, which would count as resident.
    env = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":quarantine_size_mb=4")
    proc = subprocess.run([sys.executable, "-c", code, str(stdin_rows), *map(str, args)], capture_output=True,
                          text=True, timeout=600, env=env)
    rc, rss = proc.stdout.split()
    return int(rc), int(rss), proc.stderr


def test_eval_pairs_streams_a_file_in_bounded_memory(cli, lambert, tmp_path):
    """Read twice (checked, then evaluated a block at a time): memory does not grow with the rows, and
    a bad row at the end still prints nothing."""
    few, many = tmp_path / "few.csv", tmp_path / "many.csv"
    few.write_text("0,0,1,0.1,0.2,0.97\n" * 1000)
    many.write_text("0,0,1,0.1,0.2,0.97\n" * 300_000)
    small_rc, small_rss, _ = rss_mb([cli, "eval", lambert, "--pairs", few])
    big_rc, big_rss, _ = rss_mb([cli, "eval", lambert, "--pairs", many])
    assert small_rc == 0 and big_rc == 0
    # Held whole, 300 k rows of ~135 bytes would add ~40 MB.
    assert big_rss < small_rss + 20, (small_rss, big_rss)
    with open(many, "a") as f:
        f.write("0,0,1\n")
    proc = run(cli, "eval", lambert, "--pairs", many, check=False)
    assert proc.returncode == 1 and proc.stdout == ""
    assert one_error_line(proc).startswith(f"brdfz: {many}:300001: expected 6 comma-separated numbers")
    rows = run(cli, "eval", lambert, "--pairs", few).stdout.splitlines()
    assert len(rows) == 1000 and len(set(rows)) == 1


@pytest.mark.heavy  # 10^7 rows through a pipe, read once: about 10 s in Release
def test_eval_pairs_streams_ten_million_rows_from_a_pipe_in_bounded_memory(cli, lambert):
    rc, rss, err = rss_mb([cli, "eval", lambert, "--pairs", "/dev/stdin"], stdin_rows=10_000_000)
    assert rc == 0, err
    # Held whole, 10^7 rows would take ~1.3 GB.
    assert rss < 100, rss
