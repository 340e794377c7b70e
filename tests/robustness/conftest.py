"""The sweep's pytest files use tests/python's fixtures (the built command, the demo table, real-data
locations) and helpers, loaded from there rather than copied."""
import importlib.util
import pathlib

_spec = importlib.util.spec_from_file_location(
    "brdfz_python_conftest", pathlib.Path(__file__).resolve().parents[1] / "python" / "conftest.py")
_shared = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_shared)

cli, demo_table, merl_tables, rgl_files = _shared.cli, _shared.demo_table, _shared.merl_tables, _shared.rgl_files
run, import_brdfz, SHARED = _shared.run, _shared.import_brdfz, _shared.SHARED
pytest_configure = _shared.pytest_configure
