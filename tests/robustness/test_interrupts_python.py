"""Stopping the Python package's long operations, and its messages: a progress callable that raises
stops the work at that call and no output is written; Ctrl-C (SIGINT) stops compress, trial, metrics,
fit, compress(auto=True) and save within a bound, writing nothing; `threads` beyond MAX_THREADS is a
ValueError; scene dicts with NaN or numpy values, scene files with bad values and random numbers
outside [0, 1) are reported by what they are."""
import re
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from conftest import import_brdfz

FORMATS = [".binary", ".brdfz", ".exr", ".npy"]


# Session-scoped and first in each test's arguments: without the module a test skips before any other
# fixture is made.
@pytest.fixture(scope="session")
def brdfz():
    return import_brdfz()


@pytest.fixture(scope="module")
def table(brdfz, glossy):
    """A glossy model on MERL's grid (90x90x180): saved on another grid, it is tabulated again."""
    return brdfz.tabulate(brdfz.load(glossy), (90, 90, 180))


class Raiser:
    """A progress callable raising at its first call, counting its calls."""

    def __init__(self):
        self.calls = 0

    def __call__(self, fraction):
        self.calls += 1
        raise ZeroDivisionError("stop here")


def left(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("ext", FORMATS)
def test_a_raising_progress_callable_stops_save_and_convert_and_nothing_is_written(brdfz, small_table, table,
                                                                                 tmp_path, ext):
    for call in (lambda p, out: brdfz.save(table, out, res=(45, 45, 90), progress=p),
                 lambda p, out: brdfz.convert(small_table, out, res=(45, 45, 90), progress=p)):
        raiser = Raiser()
        with pytest.raises(ZeroDivisionError, match="stop here"):
            call(raiser, tmp_path / f"x{ext}")
        assert raiser.calls == 1
        assert left(tmp_path) == []


def test_a_raising_progress_callable_stops_compress_at_once(brdfz, table):
    """One raise: no further candidates are built (auto), no further iterations run (a spec)."""
    slow = "svd:rank=8,iterations=100000,res=90x90x180"  # several seconds
    t0 = time.monotonic()
    brdfz.trial(table, "tabular:res=4x4x8")  # what the first candidate costs
    cheap = time.monotonic() - t0
    for call in (lambda p: brdfz.compress(table, auto=True, max_error=1e-12, progress=p,
                                          candidates=["tabular:res=4x4x8", slow, slow]),
                 lambda p: brdfz.compress(table, slow, progress=p),
                 lambda p: brdfz.trial(table, slow, progress=p)):
        raiser = Raiser()
        t0 = time.monotonic()
        with pytest.raises(ZeroDivisionError):
            call(raiser)
        assert time.monotonic() - t0 < 2 * cheap + 1.0 and raiser.calls == 1


CHILD = textwrap.dedent("""
    import sys, brdfz
    model = brdfz.load(sys.argv[1])
    table = brdfz.tabulate(model, (90, 90, 180))
    out = sys.argv[2]
    calls = {
        "compress": lambda: brdfz.compress(table, "nmf:rank=8,iterations=100000"),
        "trial": lambda: brdfz.trial(table, "nmf:rank=8,iterations=100000"),
        "metrics": lambda: brdfz.metrics(table, table, over="directions", directions=2**29),
        "fit": lambda: brdfz.fit(table, "lambert+ggx+ggx", starts=1000, samples=10**6, max_seconds=300),
        "auto": lambda: brdfz.compress(table, auto=True, max_error=1e-12),
        "save": lambda: brdfz.save(model, out, res=(256, 128, 512)),
    }
    print("started", flush=True)
    try:
        calls[sys.argv[3]]()
        print("finished")
    except KeyboardInterrupt:
        print("interrupted")
""")


# Each operation runs for tens of seconds to minutes uninterrupted; the test waits at most 10 s for one.
@pytest.mark.heavy
@pytest.mark.parametrize("what", ["compress", "trial", "metrics", "fit", "auto", "save"])
def test_ctrl_c_stops_a_long_operation_at_once_and_writes_nothing(brdfz, glossy, tmp_path, what):
    out = tmp_path / "out.binary"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(glossy), str(out), what],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline() == "started\n"
    time.sleep(0.8)  # into the work
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        stdout, stderr = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail(f"{what} did not stop within 10 s of SIGINT")
    assert stdout == "interrupted\n", stderr
    assert time.monotonic() - sent < 2.0
    assert left(tmp_path) == []


def test_threads_beyond_the_limit_is_a_value_error(brdfz, table, tmp_path):
    assert brdfz.MAX_THREADS == 1024
    message = r"^threads = 1000000000 is above the limit of 1024 \(0: one per hardware thread\)$"
    for call in (lambda: brdfz.compress(table, "tabular:res=4x4x8", threads=10**9),
                 lambda: brdfz.trial(table, "tabular:res=4x4x8", threads=10**9),
                 lambda: brdfz.metrics(table, table, over="directions", directions=64, threads=10**9),
                 lambda: brdfz.fit(table, "lambert", threads=10**9),
                 lambda: brdfz.tabulate(table, (4, 4, 8), threads=10**9),
                 lambda: brdfz.save(table, tmp_path / "x.binary", res=(4, 4, 8), threads=10**9),
                 lambda: brdfz.compress(table, auto=True, max_error=0.5, candidates=["tabular:res=4x4x8"],
                                        threads=10**9)):
        with pytest.raises(ValueError, match=message):
            call()
    assert left(tmp_path) == []


def test_scene_dicts_name_a_value_that_is_not_finite_and_take_numpy_values(brdfz):
    scene = {"lights": [{"direction": [0, 0, 1], "intensity": 2.0}],
             "views": [{"axis": [0, 0.3, 0.95], "max_angle_deg": 30, "count": 8}]}
    plain = brdfz.read_scene(scene)
    numpy_values = {"lights": [{"direction": np.array([0.0, 0.0, 1.0]), "intensity": np.float32(2.0)}],
                    "views": [{"axis": np.array([0, 0.3, 0.95]), "max_angle_deg": np.int64(30),
                               "count": np.int32(8)}]}
    assert brdfz.read_scene(numpy_values).samples == plain.samples > 0
    for bad, where in [(float("nan"), "lights[0].intensity"), (np.float64("inf"), "lights[0].intensity")]:
        spoilt = {**scene, "lights": [{"direction": [0, 0, 1], "intensity": bad}]}
        with pytest.raises(ValueError, match=rf"^scene dict: {re.escape(where)}: (nan|inf) is not a finite number$"):
            brdfz.read_scene(spoilt)
    with pytest.raises(ValueError, match=r"^scene dict: views\[0\]\.axis\[1\]: a value of type object is not JSON$"):
        brdfz.read_scene({**scene, "views": [{"axis": [0, object(), 1], "max_angle_deg": 30, "count": 8}]})


def test_a_scene_value_refused_after_parsing_names_the_file(brdfz, tmp_path):
    path = tmp_path / "scene.json"
    path.write_text('{"format": "brdfz-scene", "version": 1, "lights": [{"direction": [0, 0, 1], '
                    '"intensity": -1}], "views": [{"axis": [0, 0, 1], "max_angle_deg": 30, "count": 4}]}')
    with pytest.raises(ValueError, match=rf"^{path}: scene: lights\[0\]\.intensity must be finite and >= 0$"):
        brdfz.read_scene(path)
    with pytest.raises(ValueError, match=r"^scene dict: scene: lights\[0\]\.intensity must be finite and >= 0$"):
        brdfz.read_scene({"lights": [{"direction": [0, 0, 1], "intensity": -1}],
                          "views": [{"axis": [0, 0, 1], "max_angle_deg": 30, "count": 4}]})


@pytest.mark.parametrize("u, text", [(-1e-300, "-1e-300"), (1.0000000000000002, "1.0000000000000002"),
                                     (-5e-324, "-5e-324")])
def test_random_numbers_outside_the_unit_interval_are_printed_as_they_are(table, u, text):
    wo = np.array([[0.0, 0.3, 0.95]] * 2)
    uu = np.full((2, 2), 0.5)
    uu[1, 0] = u
    with pytest.raises(ValueError, match=rf"^u\[1\]: {text} is outside \[0, 1\)$"):
        table.sample(wo, uu)
