"""brdfz.batch on a Dask LocalCluster of 2 workers and on the shared RGL files: the catalogue is complete
and equals what `brdfz diff` measures on the written files; a corrupt input fails alone; a rerun does no
work; a worker killed during a task leaves the batch to finish; Ctrl-C leaves a valid catalogue."""
import csv
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time

import pytest

from conftest import import_brdfz, run

brdfz = import_brdfz()
distributed = pytest.importorskip("distributed", reason="Dask is not installed (scripts/setup-deps)")
batch = pytest.importorskip("brdfz.batch")

SPECS = ["tabular:res=16x16x32", "svd:rank=2,res=32x16x16"]
MATERIALS = ["paper_white_rgb", "cardboard_rgb", "satin_rosaline_rgb"]
REQUIRED = ["material", "spec", "status", "bytes", "cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse", "eval_rate",
            "build_seconds", "output", "error"]


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def as_text(rows):
    """Returned rows as the catalogue's CSV spells them."""
    return [{c: batch.report.fmt(r.get(c)) for c in batch.COLUMNS} for r in rows]


def stray_files(out):
    return [p for p in pathlib.Path(out).rglob("*") if ".tmp" in p.name]


@pytest.fixture(scope="module")
def cluster():
    # Each worker declares 2 GB of MEMORY, as the batch's own LocalCluster does with its share.
    c = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, memory_limit="3GB",
                                 resources={"MEMORY": 2e9}, dashboard_address=":0")
    yield c
    c.close()


@pytest.fixture(scope="module")
def inputs(rgl_files, tmp_path_factory):
    """Three shared RGL files and a corrupt one (a real file cut short)."""
    by_stem = {f.stem: f for f in rgl_files}
    files = [by_stem[m] for m in MATERIALS]
    corrupt = tmp_path_factory.mktemp("corrupt") / "broken_rgb.bsdf"
    corrupt.write_bytes(files[0].read_bytes()[:100_000])
    return files, corrupt


@pytest.fixture(scope="module")
def first(cluster, inputs, tmp_path_factory):
    files, corrupt = inputs
    out = tmp_path_factory.mktemp("batch")
    rows = batch.run([*files, corrupt], SPECS, out, scheduler=cluster.scheduler_address, budgets=[0.05])
    return out, rows


def test_catalogue_complete(first, inputs):
    out, rows = first
    files, corrupt = inputs
    cat = read_csv(out / "catalogue.csv")
    assert list(cat[0]) == batch.COLUMNS and set(REQUIRED) <= set(batch.COLUMNS)
    # One row per task, in input order, and the rows run() returned are the catalogue's.
    assert [(r["material"], r["spec"]) for r in cat] == [(f.stem, s) for f in [*files, corrupt] for s in SPECS]
    assert cat == as_text(rows)
    for r in cat[:-2]:
        assert r["status"] == "ok" and r["error"] == "" and r["over"] == "directions"
        assert r["output"] == f"{r['material']}/{batch.spec_hash(r['spec'])}.brdfz"
        assert int(r["bytes"]) > 0 and float(r["eval_rate"]) > 0 and float(r["build_seconds"]) > 0
        assert r["brdfz_version"] == brdfz.__version__ and r["worker"].startswith("tcp://")
        assert r["input_sha256"] == batch.file_sha256(r["input"])
        assert json.loads((out / r["output"]).with_suffix(".json").read_text())["row"]["output"] == r["output"]
    assert not stray_files(out)


def test_catalogue_equals_diff(first, cli):
    """Every ok row's numbers are what the CLI measures over directions (the default) on the written file
    against its material, and the file holds its spec and its errors over the grid."""
    out, rows = first
    for r in rows:
        if r["status"] != "ok":
            continue
        diff = json.loads(run(cli, "diff", r["input"], out / r["output"], "--over", "directions", "--json").stdout)
        for m in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"):
            assert r[m] == pytest.approx(diff[m]["mean"], rel=1e-9), (r["material"], r["spec"], m)
        info = json.loads(run(cli, "info", out / r["output"], "--json").stdout)
        assert info["nbytes"] == r["bytes"] and info["container"]["build_spec"] == r["spec"]
        assert info["container"]["source"]["sha256"] == r["input_sha256"]
        grid = json.loads(run(cli, "diff", r["input"], out / r["output"], "--json").stdout)
        assert info["container"]["achieved"]["cos_rmse_rel"] == pytest.approx(grid["cos_rmse_rel"]["mean"], rel=1e-9)
        assert os.path.getsize(out / r["output"]) == r["file_bytes"]


def test_corrupt_input_fails_alone(first, inputs):
    out, rows = first
    _, corrupt = inputs
    failed = [r for r in rows if r["status"] != "ok"]
    assert [(r["material"], r["spec"]) for r in failed] == [("broken_rgb", s) for s in SPECS]
    for r in failed:
        assert str(corrupt) in r["error"] and "\n" not in r["error"]
        assert r["bytes"] is None and r["output"] is None
    assert not (out / "broken_rgb").exists() or not any((out / "broken_rgb").iterdir())


def test_charts_and_summary(first):
    out, _ = first
    pytest.importorskip("matplotlib")
    for png in ["size_vs_cos_rmse_rel.png", "speed_vs_error.png", "auto_size_vs_error.png"]:
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    summary = (out / "summary.md").read_text()
    assert "broken_rgb" in summary and "(catalogue.csv)" in summary
    assert "Smallest setting within each cos_rmse_rel budget" in summary


def test_parquet(first):
    pq = pytest.importorskip("pyarrow.parquet", reason="pyarrow is not installed")
    out, rows = first
    table = pq.read_table(out / "catalogue.parquet").to_pylist()
    assert [r["bytes"] for r in table] == [r["bytes"] for r in rows]
    assert [r["cos_rmse_rel"] for r in table] == [r["cos_rmse_rel"] for r in rows]


def test_rerun_does_no_work(first, inputs):
    """The same batch again reuses every row without contacting a scheduler (this one does not exist)."""
    out, rows = first
    files, _ = inputs
    mtimes = {p: p.stat().st_mtime_ns for p in out.rglob("*.brdfz")}
    again = batch.run(files, SPECS, out, scheduler="tcp://127.0.0.1:9", charts=False)
    assert again == rows[:-2]
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*.brdfz")} == mtimes


def test_serial_changed_input_and_force(first, inputs, tmp_path):
    """--workers 1 runs without Dask and measures what the cluster measured; a changed input is rebuilt,
    an unchanged one reused, and force rebuilds."""
    out, rows = first
    files, _ = inputs
    material = tmp_path / "in" / f"{files[0].stem}.bsdf"
    material.parent.mkdir()
    shutil.copy(files[0], material)
    serial = batch.run([material], SPECS[:1], tmp_path / "out", workers=1, charts=False)
    assert serial[0]["bytes"] == rows[0]["bytes"]
    for m in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"):  # sums over other thread counts
        assert serial[0][m] == pytest.approx(rows[0][m], rel=1e-12)
    assert serial[0]["worker"] == "local"
    assert batch.run([material], SPECS[:1], tmp_path / "out", workers=1, charts=False) == serial
    shutil.copy(files[1], material)  # same name, other data
    changed = batch.run([material], SPECS[:1], tmp_path / "out", workers=1, charts=False)
    assert changed[0]["input_sha256"] == batch.file_sha256(files[1])
    assert changed[0]["cos_rmse"] == pytest.approx(rows[2]["cos_rmse"], rel=1e-12)
    forced = batch.run([material], SPECS[:1], tmp_path / "out", workers=1, charts=False, force=True)
    assert forced[0]["started"] >= changed[0]["started"] and forced[0]["load_seconds"] != changed[0]["load_seconds"]


def test_worker_killed_during_a_task(cluster, inputs, tmp_path):
    """SIGKILL a worker while it runs a task: Dask runs the task again on a live worker, and the batch
    finishes with every row ok and no partial file."""
    files, _ = inputs
    client = distributed.Client(cluster)
    specs = ["tabular:res=45x45x90", "svd:rank=2,res=32x16x16"]
    result = {}
    thread = threading.Thread(target=lambda: result.setdefault(
        "rows", batch.run(files[:2], specs, tmp_path, scheduler=cluster.scheduler_address, charts=False)))
    thread.start()

    def executing(dask_worker):
        return [(ts.key, ts.resource_restrictions) for ts in dask_worker.state.executing]

    pids = client.run(os.getpid)
    victim = killed = None
    deadline = time.monotonic() + 120
    while victim is None and time.monotonic() < deadline and thread.is_alive():
        for address, running in client.run(executing).items():
            builds = [(k, res) for k, res in running if str(k).startswith("build_task-")]
            if builds:
                victim, (killed, restrictions) = address, builds[0]
                os.kill(pids[address], signal.SIGKILL)
                break
        time.sleep(0.05)
    thread.join(300)
    client.close()
    assert victim is not None, "no task was seen running"
    rows = result["rows"]
    assert [r["status"] for r in rows] == ["ok"] * 4
    # The killed task (its key names material/spec-hash) finished elsewhere, declaring its memory.
    material, digest = str(killed).split("-", 1)[1].rsplit("-", 1)[0].split("/")
    row = next(r for r in rows if r["material"] == material and batch.spec_hash(r["spec"]) == digest)
    assert row["worker"] != victim
    assert restrictions == {"MEMORY": min(batch.estimate_memory(os.path.getsize(row["input"]), row["spec"]), 2e9)}
    assert not stray_files(tmp_path)
    for r in rows:
        assert brdfz.load(tmp_path / r["output"]).nbytes == r["bytes"]


def test_local_cluster_declares_memory():
    """The LocalCluster an Engine starts gives each worker its MEMORY; a task declaring more than any
    worker has is clamped to the largest, so it runs instead of waiting forever."""
    with batch.Engine(workers=2, memory_per_worker=int(1.5e9)) as engine:
        engine.start()
        workers = engine.client.scheduler_info()["workers"].values()
        assert [w["resources"] for w in workers] == [{"MEMORY": 1.5e9}] * 2
        done = list(engine.map([batch.Job(os.getpid, (), "pid", memory=int(8e9))], "pid"))
    assert len(done) == 1 and done[0][2] == "" and done[0][1] != os.getpid()


def test_ctrl_c_leaves_a_valid_catalogue(inputs, tmp_path):
    files, _ = inputs
    env = dict(os.environ)
    proc = subprocess.Popen([sys.executable, "-m", "brdfz.batch", *map(str, files), "--specs", *SPECS,
                             "tabular:res=45x45x90", "--out", tmp_path, "--workers", "2", "--no-charts"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 180
    while not list(tmp_path.glob("*/*.json")) and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted" in err
    cat = read_csv(tmp_path / "catalogue.csv")
    assert 1 <= len(cat) < len(files) * 3
    for r in cat:
        assert r["status"] == "ok" and brdfz.load(tmp_path / r["output"]).nbytes == int(r["bytes"])
    assert not stray_files(tmp_path)


def test_command_line(inputs, tmp_path):
    files, corrupt = inputs
    cmd = [sys.executable, "-m", "brdfz.batch"]
    ok = subprocess.run([*cmd, files[0], "--specs", SPECS[0], "--out", tmp_path / "a", "--workers", "1", "--no-charts"],
                        capture_output=True, text=True, timeout=300)
    assert ok.returncode == 0, ok.stderr
    assert "1 of 1 tasks ok" in ok.stdout and len(read_csv(tmp_path / "a" / "catalogue.csv")) == 1
    failed = subprocess.run([*cmd, corrupt, "--specs", SPECS[0], "--out", tmp_path / "b", "--workers", "1",
                             "--no-charts"], capture_output=True, text=True, timeout=300)
    assert failed.returncode == 1 and read_csv(tmp_path / "b" / "catalogue.csv")[0]["status"] == "failed"
    missing = subprocess.run([*cmd, tmp_path / "nothing.bsdf", "--specs", SPECS[0], "--out", tmp_path / "c"],
                             capture_output=True, text=True, timeout=300)
    assert missing.returncode == 1 and missing.stderr.strip().count("\n") == 0 and "no such file" in missing.stderr
    both = subprocess.run([*cmd, files[0], "--specs", SPECS[0], "--out", tmp_path / "d", "--workers", "2",
                           "--scheduler", "tcp://127.0.0.1:9"], capture_output=True, text=True, timeout=300)
    assert both.returncode == 2 and "not allowed with" in both.stderr


def test_same_name_twice_is_an_error(inputs, tmp_path):
    files, _ = inputs
    other = tmp_path / "x" / files[0].name
    other.parent.mkdir()
    shutil.copy(files[1], other)
    with pytest.raises(ValueError, match=f"two materials named {files[0].stem}"):
        batch.run([files[0], other], SPECS, tmp_path / "out", workers=1)


@pytest.mark.skipif(not batch.measures_directions(),
                    reason="brdfz.metrics has no over= in this build (branch data adds errors over directions)")
def test_over_grid_and_both(inputs, cli, tmp_path):
    files, _ = inputs
    rows = batch.run(files[:1], SPECS[:1], tmp_path, workers=1, over="grid", charts=False)
    r = rows[0]
    assert r["status"] == "ok" and r["over"] == "grid"
    diff = json.loads(run(cli, "diff", r["input"], tmp_path / r["output"], "--json").stdout)
    for m in ("cos_rmse", "cos_rmse_rel", "log_rmse", "cbrt_rmse"):
        assert r[m] == pytest.approx(diff[m]["mean"], rel=1e-9)
    both = batch.run(files[:1], SPECS[:1], tmp_path / "both", workers=1, over=("directions", "grid"), charts=False)
    assert both[0]["grid_cos_rmse_rel"] == r["cos_rmse_rel"]
    assert both[0]["cos_rmse_rel"] != r["cos_rmse_rel"]


def test_the_command_measures_over_directions_by_default(demo_table, tmp_path):
    """python -m brdfz.batch without --over: the catalogue's errors are over direction pairs."""
    out = tmp_path / "cmd"
    assert batch.main([str(demo_table), "--specs", "tabular:res=8x8x16", "--out", str(out), "--workers", "1",
                       "--no-charts"]) == 0
    row = read_csv(out / "catalogue.csv")[0]
    demo = brdfz.load(demo_table)
    over = brdfz.metrics(demo, brdfz.load(out / row["output"]), over="directions").cos_rmse_rel.mean
    assert row["over"] == "directions" and float(row["cos_rmse_rel"]) == pytest.approx(over, rel=1e-5)
