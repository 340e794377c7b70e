"""brdfz.batch against a hostile user: material names that would leave --out, modes that ignore the
umask, an output changed in place, equivalent specs, a scheduler that cannot be reached, no Dask,
Ctrl-C with workers busy, a full disk, and --threads beyond the limit. One cheap spec on the demo's
table, run here (--workers 1) unless the case is about workers."""
import csv
import json
import os
import pathlib
import resource
import shutil
import signal
import stat
import subprocess
import sys
import time

import pytest

from conftest import import_brdfz, run

SPEC = "tabular:res=4x4x8"


# Session-scoped and first in each test's arguments: without the module a test skips before any other
# fixture is made.
@pytest.fixture(scope="session")
def batch():
    import_brdfz()
    return pytest.importorskip("brdfz.batch")


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def one_line(text):
    lines = text.strip().splitlines()
    assert len(lines) == 1, text
    return lines[0]


def command(*args):
    return [sys.executable, "-m", "brdfz.batch", *map(str, args)]


@pytest.fixture
def material(batch, small_table, tmp_path):
    """A small table (a task on it takes a fraction of a second) alone in a folder."""
    path = tmp_path / "in" / small_table.name
    path.parent.mkdir()
    shutil.copy(small_table, path)
    return path


@pytest.mark.parametrize("name", ["...bsdf", "..binary", "catalogue.csv.binary", "renders.bsdf"])
def test_a_material_name_that_is_not_a_folder_of_its_own_in_out_is_refused(batch, material, tmp_path, capsys, name):
    folder = material.parent
    shutil.copy(material, folder / name)
    out = tmp_path / "o" / "inner"
    assert batch.main([str(folder), "--specs", SPEC, "--out", str(out), "--workers", "1", "--no-charts"]) == 1
    stem = pathlib.Path(name).stem
    assert one_line(capsys.readouterr().err) == (
        f"batch: {folder / name}: the material name {stem!r} cannot be its folder in the output folder; "
        "rename the file")
    assert not (tmp_path / "o").exists()


def test_every_output_follows_the_umask_and_a_replaced_one_keeps_its_mode(batch, material, tmp_path):
    pytest.importorskip("matplotlib")  # summary.md comes with the charts
    out = tmp_path / "o"
    umask = os.umask(0o027)
    try:
        batch.run([material], [SPEC], out, workers=1)
    finally:
        os.umask(umask)
    files = [p for p in out.rglob("*") if p.is_file()]
    assert {p.suffix for p in files} >= {".csv", ".md", ".json", ".brdfz", ".png"}
    assert {p.relative_to(out).as_posix(): oct(stat.S_IMODE(p.stat().st_mode)) for p in files} == {
        p.relative_to(out).as_posix(): oct(0o640) for p in files}
    (out / "catalogue.csv").chmod(0o600)
    batch.run([material], [SPEC], out, workers=1, charts=False, force=True)
    assert stat.S_IMODE((out / "catalogue.csv").stat().st_mode) == 0o600


def test_a_rerun_rebuilds_an_output_changed_in_place(batch, material, tmp_path):
    out = tmp_path / "o"
    first = batch.run([material], [SPEC], out, workers=1, charts=False)
    output = out / first[0]["output"]
    good = output.read_bytes()
    assert batch.run([material], [SPEC], out, workers=1, charts=False) == first  # reused as it is
    output.write_bytes(os.urandom(len(good)))
    again = batch.run([material], [SPEC], out, workers=1, charts=False)
    assert again[0]["status"] == "ok" and again[0]["started"] >= first[0]["started"]
    assert batch.brdfz.load(output).nbytes == first[0]["bytes"]
    assert json.loads(output.with_suffix(".json").read_text())["output_sha256"] == batch.file_sha256(output)


def test_equivalent_spellings_of_a_spec_are_one_task(batch, material, tmp_path):
    spellings = [SPEC, "tabular:res=04x4x008", "tabular:dtype=f32,res=4x4x8", "tabular:res=4x4x8,phih=1,dwarp=0.0",
                 " tabular:lookup=linear,res=4x4x8 "]
    assert {batch.normalise_spec(s) for s in spellings} == {"tabular:res=4x4x8"}
    assert len({batch.spec_hash(s) for s in spellings}) == 1
    assert batch.normalise_spec("tabular:res=4x4x8,dwarp=0.50") == batch.normalise_spec("tabular:dwarp=.5,res=4x4x8")
    assert batch.normalise_spec("svd:rank=4") != batch.normalise_spec("svd:rank=4,res=90x90x180")  # a source's grid
    assert batch.normalise_spec("analytic:ggx+lambert") != batch.normalise_spec("analytic:lambert+ggx")
    out = tmp_path / "o"
    rows = batch.run([material], spellings, out, workers=1, charts=False)
    assert [r["spec"] for r in rows] == [SPEC]
    assert len(list(out.rglob("*.brdfz"))) == 1
    # Another spelling later reuses the task, under the spelling asked for.
    again = batch.run([material], spellings[1:2], out, workers=1, charts=False)
    assert again[0]["spec"] == spellings[1] and again[0]["started"] == rows[0]["started"]


def test_a_scheduler_that_cannot_be_reached_leaves_nothing(batch, material, tmp_path, capsys):
    dask = pytest.importorskip("dask", reason="Dask is not installed")
    out = tmp_path / "o"
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        rc = batch.main([str(material), "--specs", SPEC, "--out", str(out), "--scheduler", "tcp://127.0.0.1:1"])
    assert rc == 1
    assert one_line(capsys.readouterr().err).startswith("batch: ")
    assert not out.exists()


def test_without_dask_more_than_one_worker_is_one_line(batch, material, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` fails as if not installed
    out = tmp_path / "o"
    assert batch.main([str(material), "--specs", SPEC, "--out", str(out), "--workers", "2"]) == 1
    assert one_line(capsys.readouterr().err) == (
        "batch: Dask is not installed (pip install 'brdfz[batch]'); --workers 1 runs the tasks without it")
    assert not out.exists()


def test_threads_beyond_the_limit_is_one_line(batch, material, tmp_path, capsys):
    out = tmp_path / "o"
    assert batch.main([str(material), "--specs", SPEC, "--out", str(out), "--workers", "1", "--threads", "1000000000"]) == 1
    assert one_line(capsys.readouterr().err) == (
        "batch: threads = 1000000000 is above the limit of 1024 (0: one per hardware thread)")
    assert not out.exists()


def limited(max_bytes):
    def setup():
        resource.setrlimit(resource.RLIMIT_FSIZE, (max_bytes, max_bytes))
    return setup


def test_a_full_disk_names_the_catalogue_not_its_temporary(batch, material, tmp_path):
    """Every file larger than 300 bytes fails to be written, the catalogue's header included."""
    out = tmp_path / "o"
    proc = subprocess.run(command(material, "--specs", SPEC, "--out", out, "--workers", "1", "--no-charts"),
                          capture_output=True, text=True, timeout=300, preexec_fn=limited(300))
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines()[-1] == f"batch: [Errno 27] File too large: '{out / 'catalogue.csv'}'"
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]


def test_a_catalogue_that_cannot_be_written_is_named(batch, tmp_path):
    missing = tmp_path / "missing" / "catalogue.csv"
    with pytest.raises(FileNotFoundError) as e:
        batch.report.write_csv([], missing, batch.COLUMNS)
    assert e.value.filename == str(missing)
    if os.geteuid() != 0:  # root writes into a read-only folder
        folder = tmp_path / "read-only"
        folder.mkdir(mode=0o555)
        with pytest.raises(PermissionError) as e:
            batch.report.write_csv([], folder / "catalogue.csv", batch.COLUMNS)
        assert e.value.filename == str(folder / "catalogue.csv")


@pytest.mark.heavy  # a LocalCluster of 2 workers and a dozen tasks: about 10 s
def test_ctrl_c_with_workers_busy_leaves_the_catalogue_and_the_records_in_agreement(batch, cli, glossy, tmp_path):
    pytest.importorskip("distributed", reason="Dask is not installed")
    names = [tmp_path / f"m{k}.binary" for k in range(4)]
    run(cli, "convert", glossy, names[0], "--res", "90x90x180")  # full size: each task runs for about a second
    for name in names[1:]:
        shutil.copy(names[0], name)
    out = tmp_path / "o"
    specs = ["tabular:res=45x45x90", "svd:rank=2,res=45x45x90", "tabular:res=32x32x64"]
    proc = subprocess.Popen(command(*names, "--specs", *specs, "--out", out, "--workers", "2", "--no-charts"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(out.glob("*/*.json")) and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    rows = read_csv(out / "catalogue.csv")
    assert 1 <= len(rows) < len(names) * len(specs)
    recorded = {p.relative_to(out).with_suffix(".brdfz").as_posix() for p in out.glob("*/*.json")}
    assert {r["output"] for r in rows} == recorded
    assert {p.relative_to(out).as_posix() for p in out.glob("*/*.brdfz")} >= recorded
