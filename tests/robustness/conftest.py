"""The sweep's pytest files use tests/python's fixtures (the built command, the demo table, real-data
locations) and helpers, loaded from there rather than copied, and a small material of their own."""
import importlib.util
import pathlib

import pytest

_spec = importlib.util.spec_from_file_location(
    "brdfz_python_conftest", pathlib.Path(__file__).resolve().parents[1] / "python" / "conftest.py")
_shared = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_shared)

cli, demo_table, merl_tables, rgl_files = _shared.cli, _shared.demo_table, _shared.merl_tables, _shared.rgl_files
run, import_brdfz, SHARED = _shared.run, _shared.import_brdfz, _shared.SHARED
pytest_configure = _shared.pytest_configure


GLOSSY = ('{"format": "brdfz-analytic", "version": 1, "model": "lambert+ggx", "parameters": {"lambert.rho_r": 0.5, '
          '"lambert.rho_g": 0.2, "lambert.rho_b": 0.05, "ggx.ks_r": 0.8, "ggx.ks_g": 0.8, "ggx.ks_b": 0.8, '
          '"ggx.alpha": 0.12, "ggx.f0": 0.05}}')


@pytest.fixture(scope="session")
def glossy(tmp_path_factory):
    """An analytic model file (lambert+ggx): a material without the demo's run of the command."""
    path = tmp_path_factory.mktemp("glossy") / "glossy.json"
    path.write_text(GLOSSY)
    return path


@pytest.fixture(scope="session")
def small_table(cli, glossy, tmp_path_factory):
    """That model as a MERL table of 16x16x32 bins: cheap to load, even under the sanitizers."""
    path = tmp_path_factory.mktemp("small") / "glossy.binary"
    run(cli, "convert", glossy, path, "--res", "16x16x32")
    return path
