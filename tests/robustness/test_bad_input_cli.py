"""The bad-input sweep on the command, one test per defect it found: exit statuses, specs, pairs files,
bounds checked before work, seeds, streamed samples, diff and fit reports."""
import json
import os
import pty
import struct
import subprocess
import sys

import pytest

from conftest import run

PAIR = "0.1,0.2,0.97,-0.3,0.1,0.95"


def one_error_line(proc):
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    return lines[0]


@pytest.mark.parametrize("args", [
    [],                                     # no subcommand
    ["info"],                               # FILE missing
    ["info", "a", "b", "c"],                # extra arguments
    ["sample", "x.binary", "--wo", "0,0,1", "-n", "0"],  # outside -n's range
    ["eval", "x.binary", "--wi", "0,0,1"],  # --wi needs --wo
    ["fit", "x.binary", "--model", "lambert", "-o", "x.json", "--starts", "many"],
    ["bogus-command"],
])
def test_usage_errors_exit_1(cli, args):
    assert run(cli, *args, check=False).returncode == 1


def test_help_exits_0(cli):
    assert run(cli, "--help").returncode == 0
    assert run(cli, "sample", "--help").returncode == 0


def test_misspelt_candidate_exits_1_before_any_build(cli, demo_table, tmp_path):
    out = tmp_path / "x.brdfz"
    for candidate, message in [("bogus:res=4x4x8", "unknown representation 'bogus'"),
                               ("tabular:rse=4x4x8", "tabular: unknown option(s) rse"),
                               ("tabular:wibble", "tabular: unknown option(s) wibble")]:
        proc = run(cli, "compress", demo_table, "-o", out, "--auto", "--max-error", "0.5", "--candidate", candidate,
                   check=False)
        assert proc.returncode == 1, (candidate, proc.stderr)
        assert message in one_error_line(proc)
        assert not out.exists()


def test_only_an_unmet_budget_exits_2(cli, demo_table, tmp_path):
    out = tmp_path / "x.brdfz"
    proc = run(cli, "compress", demo_table, "-o", out, "--auto", "--max-error", "1e-12",
               "--candidate", "tabular:res=4x4x8", check=False)
    assert proc.returncode == 2
    assert "no candidate meets the budget" in one_error_line(proc)
    assert not out.exists()


@pytest.mark.parametrize("spec", ["tabular:wibble", "svd:foo", "tabular:res", "bivariate:dtype"])
def test_bare_word_in_spec_is_an_error_naming_it(cli, demo_table, tmp_path, spec):
    kind, word = spec.split(":")
    proc = run(cli, "compress", demo_table, "-o", tmp_path / "x.brdfz", "--repr", spec, check=False)
    assert proc.returncode == 1 and not (tmp_path / "x.brdfz").exists()
    if word in ("res", "dtype"):  # a key without its value
        assert one_error_line(proc) == f"brdfz: {kind}: option {word} needs a value ({word}=...)"
        return
    # As a misspelt key is reported.
    assert one_error_line(proc) == f"brdfz: {kind}: unknown option(s) {word}"
    proc = run(cli, "compress", demo_table, "-o", tmp_path / "x.brdfz", "--repr", f"{kind}:{word}=1", check=False)
    assert one_error_line(proc) == f"brdfz: {kind}: unknown option(s) {word}"


def test_demo_with_a_bad_repr_fails(cli, tmp_path):
    for spec in ["bogus", "tabular:wibble", "tabular:res=0x1x1"]:
        proc = run(cli, "demo", "--out", tmp_path / "d", "--repr", spec, check=False)
        assert proc.returncode == 1, (spec, proc.stdout)
        assert one_error_line(proc).startswith("brdfz: ")


@pytest.mark.parametrize("first_row", [
    "0.1,0.2,0.97,-0.3,0.1,0.95,0.5",   # 7 columns
    "0.1,0.2,0.97,-0.3,0.1",            # 5 columns
    "0.1;0.2;0.97;-0.3;0.1;0.95",       # ';' separators
    "0.1,,0.97,-0.3,0.1,0.95",          # an empty cell
    "1e,0.2,0.97,-0.3,0.1,0.95",        # a malformed number
    "wix,0.2,0.97,-0.3,0.1,0.95",       # a word among numbers
])
def test_malformed_first_pairs_row_is_an_error_naming_it(cli, demo_table, tmp_path, first_row):
    pairs = tmp_path / "pairs.csv"
    pairs.write_text(f"{first_row}\n{PAIR}\n{PAIR}\n")
    proc = run(cli, "eval", demo_table, "--pairs", pairs, check=False)
    assert proc.returncode == 1 and proc.stdout == ""
    assert one_error_line(proc).startswith(f"brdfz: {pairs}:1: expected 6 comma-separated numbers")


@pytest.mark.parametrize("text", [
    f"wix,wiy,wiz,wox,woy,woz\n{PAIR}\n{PAIR}\n",          # a header
    f"\n\nwix;wiy;wiz;wox;woy;woz\n{PAIR}\n{PAIR}\n",     # a header after blank lines
    f"\ufeff{PAIR}\n{PAIR}\n",                            # a byte order mark before data
    f"\ufeffwix,wiy,wiz,wox,woy,woz\r\n{PAIR}\r\n{PAIR}\r\n",
])
def test_pairs_rows_line_up_with_output_rows(cli, demo_table, tmp_path, text):
    pairs = tmp_path / "pairs.csv"
    pairs.write_text(text, encoding="utf-8")
    proc = run(cli, "eval", demo_table, "--pairs", pairs)
    assert len(proc.stdout.splitlines()) == 2


def test_a_header_after_data_is_an_error(cli, demo_table, tmp_path):
    pairs = tmp_path / "pairs.csv"
    pairs.write_text(f"{PAIR}\nwix,wiy,wiz,wox,woy,woz\n")
    assert one_error_line(run(cli, "eval", demo_table, "--pairs", pairs, check=False)).startswith(f"brdfz: {pairs}:2:")


def child_rss_mb(args):
    """Runs the command and returns (CompletedProcess, its peak RSS in MB)."""
    code = ("import resource, subprocess, sys\n"
            "p = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)\n"
            "print(p.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss // 1024)\n"
            "sys.stderr.write(p.stderr.decode())\n")
    # Under AddressSanitizer freed memory waits in a quarantine, which would count as resident.
    env = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":quarantine_size_mb=4")
    proc = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, timeout=600,
                          env=env)
    rc, rss = proc.stdout.split()
    return int(rc), int(rss), proc.stderr


@pytest.mark.heavy  # 1.5 M rows; under the sanitizers their allocator's own memory is what is measured
def test_sample_streams_rows_in_constant_memory(cli, tmp_path):
    run(cli, "demo", "--out", tmp_path, "--repr", "tabular:res=4x4x8")
    table = tmp_path / "coated-diffuse.binary"
    small_rc, small_rss, _ = child_rss_mb([cli, "sample", table, "--wo", "0,0.3,0.95", "-n", "1000"])
    big_rc, big_rss, _ = child_rss_mb([cli, "sample", table, "--wo", "0,0.3,0.95", "-n", "1500000"])
    assert small_rc == 0 and big_rc == 0
    # Buffered, 1.5 M rows of ~180 bytes would add ~270 MB.
    assert big_rss < small_rss + 40, (small_rss, big_rss)
    rows = run(cli, "sample", table, "--wo", "0,0.3,0.95", "-n", "10000").stdout.splitlines()
    assert len(rows) == 10001 and rows[0].startswith("wix,")


@pytest.mark.parametrize("seed", ["-1", "18446744073709551616", "1e30", "3.5", "", "0x10"])
def test_sample_seed_out_of_range_is_refused(cli, demo_table, seed):
    proc = run(cli, "sample", demo_table, "--wo", "0,0,1", "-n", "1", f"--seed={seed}", check=False)
    assert proc.returncode == 1 and proc.stdout == ""


def test_sample_seed_full_range_is_accepted(cli, demo_table):
    for seed in ["0", "18446744073709551615"]:
        assert len(run(cli, "sample", demo_table, "--wo", "0,0,1", "-n", "2", "--seed", seed).stdout.splitlines()) == 3


def test_fit_starts_capped_before_loading(cli, tmp_path):
    proc = run(cli, "fit", tmp_path / "missing.binary", "--model", "lambert", "-o", tmp_path / "m.json",
               "--starts", "1000000", check=False)
    assert proc.returncode == 1
    assert "--starts" in one_error_line(proc) and "1000" in proc.stderr and "missing" not in proc.stderr
    assert run(cli, "fit", tmp_path / "m.binary", "--model", "lambert", "-o", tmp_path / "m.json", "--starts", "0",
               check=False).returncode == 1


def test_fit_shows_progress_on_a_terminal(cli, demo_table, tmp_path):
    """Progress goes to stderr when it is a terminal (a pty here)."""
    out = tmp_path / "m.json"
    leader, follower = pty.openpty()
    proc = subprocess.run([cli, "fit", demo_table, "--model", "lambert", "-o", out, "--starts", "40",
                           "--samples", "2000"], stdout=subprocess.PIPE, stderr=follower, timeout=300)
    os.close(follower)
    seen = b""
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    os.close(leader)
    assert proc.returncode == 0
    assert b"\rfitting " in seen and b"fitting 100%" in seen
    assert b"starts       40, best #" in proc.stdout


def test_fit_without_a_usable_start_never_prints_best_minus_one(cli, tmp_path):
    n = 90 * 90 * 180
    values = [-1.0] * n
    for k in range(0, n, 400):
        values[k] = 0.0  # measured, all zero: nothing to fit
    table = tmp_path / "zeros.binary"
    table.write_bytes(struct.pack("<3i", 90, 90, 180) + struct.pack(f"<{3 * n}d", *(values * 3)))
    proc = run(cli, "fit", table, "--model", "lambert", "-o", tmp_path / "m.json", check=False)
    assert proc.returncode == 1
    assert "#-1" not in proc.stdout and "none usable" in proc.stdout
    assert "insufficient data" in one_error_line(proc)


def test_grid_limits_refused_up_front_with_the_bytes(cli, demo_table, tmp_path):
    for spec in ["tabular:res=1024x1024x1024", "tabular:res=4096x4096x4096"]:
        rc, rss, err = child_rss_mb([cli, "compress", demo_table, "-o", tmp_path / "x.brdfz", "--repr", spec])
        assert rc == 1 and "over the limit of 67108864 bins (805306368 bytes)" in err and "bytes" in err
        assert rss < 200, rss  # refused before the table is allocated
    rc, _, err = child_rss_mb([cli, "convert", demo_table, tmp_path / "x.binary", "--res", "1024x1024x512"])
    assert rc == 1 and "6442450944 bytes" in err
    # A MERL header of 1024x1024x512 (a sparse file of the size it declares), refused by its dimensions.
    header = tmp_path / "header.binary"
    with open(header, "wb") as f:
        f.write(struct.pack("<3i", 1024, 1024, 512))
        f.truncate(12 + 3 * 8 * 1024 * 1024 * 512)
    rc, rss, err = child_rss_mb([cli, "info", header])
    assert rc == 1 and "MERL dimensions: grid 1024x1024x512: 536870912 bins, a float32 table of 6442450944 bytes" in err
    assert rss < 200, rss


def test_diff_of_a_file_against_itself_is_zero(cli, demo_table, tmp_path):
    for a in [demo_table, tmp_path / "copy.brdfz"]:
        if a.suffix == ".brdfz":
            run(cli, "convert", demo_table, a)
        report = json.loads(run(cli, "diff", a, a, "--json").stdout)
        for metric in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"):
            assert report[metric]["mean"] == 0.0, (a, metric, report[metric])


def test_diff_against_a_reference_without_reflectance_is_an_error(cli, demo_table, tmp_path):
    """ALTA measurements that are all negative (kept as measured): cos_rmse_rel would be inf."""
    alta = tmp_path / "negative.dat"
    rows = "\n".join(f"{0.05 * k} {0.1 + 0.05 * k} 1.0 -0.{k + 1}" for k in range(6))
    alta.write_text("#DIM 3 1\n#PARAM_IN RUSIN_TH_TD_PD\n" + rows + "\n")
    proc = run(cli, "diff", alta, demo_table, check=False)
    assert proc.returncode == 1 and "inf" not in proc.stdout
    assert "zero or negative at every sample" in one_error_line(proc)


def info_lines(cli, path):
    """info's text lines as key -> rest ("dims", "valid", "range", ...)."""
    out = {}
    for line in run(cli, "info", path).stdout.splitlines()[1:]:
        key, _, rest = line.strip().partition(" ")
        out.setdefault(key, rest.strip())
    return out


def test_info_and_convert_say_what_a_stored_representation_holds(cli, demo_table, tmp_path):
    """svd factors, analytic parameters and RGL tensors in a container: their grid, parameters or
    tensor and how many entries are valid, not "dims -, valid 0, range [0, 0]"."""
    svd = tmp_path / "s.brdfz"
    run(cli, "compress", demo_table, "-o", svd, "--repr", "svd:rank=2,res=16x16x32")
    model = tmp_path / "lambert.json"
    model.write_text('{"format": "brdfz-analytic", "version": 1, "model": "lambert", "parameters": '
                     '{"lambert.rho_r": 0.3, "lambert.rho_g": 0.4, "lambert.rho_b": 0.5}}')
    bsdf = tmp_path / "r.bsdf"
    run(cli, "convert", demo_table, bsdf, "--res", "8x8x16")
    converted = {}
    for name, src in [("svd", svd), ("analytic", model), ("rgl", bsdf)]:
        out = tmp_path / f"{name}-copy.brdfz"
        converted[name] = (out, run(cli, "convert", src, out).stdout.strip())
    info = {name: info_lines(cli, out) for name, (out, _) in converted.items()}

    assert info["svd"]["dims"] == "16x16x32 (grid of the rank-2 svd factors)"
    assert info["svd"]["valid"] == "8192" and info["svd"]["range"] == "- (nothing stored is a value of f_r)"
    assert converted["svd"][1].endswith(": 8192 valid entries")
    assert info["analytic"]["dims"] == "3 (parameters)" and info["analytic"]["valid"] == "3"
    assert info["analytic"]["range"] == "[0.3, 0.5] (parameter values)"
    assert converted["analytic"][1].endswith(": 3 valid entries")
    assert info["rgl"]["dims"].endswith("(rgb tensor of the RGL file)")
    valid = int(info["rgl"]["valid"])
    assert valid > 0 and converted["rgl"][1].endswith(f": {valid} valid entries")
    low, high = info["rgl"]["range"].removesuffix(" (stored values)").strip("[]").split(", ")
    assert float(low) >= 0 and float(high) > 0


def test_an_unknown_output_extension_lists_the_writable_formats(cli, demo_table, tmp_path):
    proc = run(cli, "compress", demo_table, "-o", tmp_path / "x.xyz", "--repr", "tabular:res=4x4x8", check=False)
    assert proc.returncode == 1 and not (tmp_path / "x.xyz").exists()
    message = one_error_line(proc)
    assert "unknown file extension '.xyz'" in message and ".exr" in message and ".brdfz" in message
    assert ".dat" not in message and ".brdf," not in message  # ALTA and Cornell are read-only
