"""Shared fixtures: the built `brdfz` command, a small MERL table, and the real-data locations."""
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


def pytest_configure(config):
    # As Catch's [heavy] tag: the sanitizer tree runs pytest with -m "not heavy" (tests/CMakeLists.txt);
    # a heavy test's code is run there by a lighter one.
    config.addinivalue_line("markers", "heavy: left to the Release run (10-60x slower under the sanitizers)")


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("BRDFZ_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("BRDFZ_CLI is not set to the built brdfz command (run through ctest)")
    return path


def run(cli, *args, check=True):
    """Run the CLI; returns the CompletedProcess (text mode)."""
    proc = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=300)
    if check and proc.returncode != 0:
        raise AssertionError(f"brdfz {' '.join(map(str, args))} failed ({proc.returncode}): {proc.stderr}")
    return proc


@pytest.fixture(scope="session")
def demo_table(cli, tmp_path_factory):
    """The demo's MERL table of the built-in material (no data files needed); one cheap representation
    instead of every one."""
    out = tmp_path_factory.mktemp("demo")
    run(cli, "demo", "--out", out, "--repr", "tabular:res=8x8x16")
    return out / "coated-diffuse.binary"


@pytest.fixture(scope="session")
def merl_tables():
    d = os.environ.get("BRDFZ_MERL_DIR")
    files = sorted(pathlib.Path(d).glob("*.binary")) if d and os.path.isdir(d) else []
    if not files:
        pytest.skip("no MERL tables generated from ../shared (missing ../shared or numpy)")
    return files


@pytest.fixture(scope="session")
def rgl_files():
    files = sorted((SHARED / "data" / "rgl").glob("*.bsdf"))
    if not files:
        pytest.skip("../shared/data/rgl is missing")
    return files


def import_brdfz():
    """The brdfz Python package. ctest sets BRDFZ_PYTHON=1 when it built the module (then a failing
    import is an error); elsewhere the binding tests skip without it."""
    if os.environ.get("BRDFZ_PYTHON") == "1":
        import brdfz

        return brdfz
    return pytest.importorskip("brdfz", reason="the brdfz Python package is not built (BRDFZ_BUILD_PYTHON=ON)")


def exported_layouts(tmp_path_factory, source, specs, folder):
    """{name: .brdfzrt path} of `source` (a real file; skips when ../shared is missing) exported as each
    spec of `specs` ({name: spec}) into a fresh temporary `folder`."""
    brdfz = import_brdfz()
    if not source.exists():
        pytest.skip(f"../shared is missing ({source})")
    out = tmp_path_factory.mktemp(folder)
    loaded = brdfz.load(source)
    paths = {name: out / f"{name}.brdfzrt" for name in specs}
    for name, spec in specs.items():
        brdfz.export(loaded, paths[name], repr=spec)
    return paths

