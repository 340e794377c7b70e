"""NumPy .npy tables (formats/npy): what brdfz writes numpy reads as the table, and back."""
import json

import numpy as np
import pytest
from conftest import import_brdfz, run


def test_numpy_reads_what_brdfz_writes(cli, demo_table, tmp_path):
    out = tmp_path / "t.npy"
    run(cli, "convert", demo_table, out)
    a = np.load(out)
    assert a.dtype == np.float32 and a.shape == (90, 90, 180, 3)
    brdfz = import_brdfz()
    if brdfz:
        np.testing.assert_array_equal(a, brdfz.load(demo_table).table)
    info = json.loads(run(cli, "info", out, "--json").stdout)
    assert info["format"] == "npy" and info["dims"] == [90, 90, 180] and info["valid"] == np.isfinite(a).all(-1).sum()


def test_brdfz_reads_what_numpy_writes(cli, tmp_path):
    rng = np.random.default_rng(3)
    table = rng.uniform(0.1, 2.0, (6, 5, 8, 3))
    table[0, 0, 0, 1] = np.nan
    table[1, 0, 0, 0] = -1.0
    table[2, 0, 0, 2] = np.inf
    for dtype in (np.float32, np.float64):
        path = tmp_path / f"t-{np.dtype(dtype).name}.npy"
        np.save(path, table.astype(dtype))
        info = json.loads(run(cli, "info", path, "--json").stdout)
        assert info["dims"] == [6, 5, 8] and (info["negative"], info["nan"], info["inf"]) == (1, 1, 1)
        assert info["valid"] == 6 * 5 * 8 - 3
        back = tmp_path / "back.npy"
        run(cli, "convert", path, back)
        b = np.load(back)
        good = np.isfinite(table) & (table >= 0)
        np.testing.assert_array_equal(b[good], table.astype(np.float32)[good])
        assert np.isnan(b[~good]).all()


@pytest.mark.parametrize("array,message", [
    (np.zeros((4, 4, 4, 2), np.float32), "shape must be"),
    (np.zeros((4, 4, 4, 3), np.int32), "NPY dtype"),
    (np.asfortranarray(np.ones((4, 4, 4, 3), np.float32)), "Fortran order"),
    (np.full((2, 2, 2, 3), np.nan, np.float32), "no valid value"),
])
def test_bad_arrays_are_refused(cli, tmp_path, array, message):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    proc = run(cli, "info", path, check=False)
    assert proc.returncode == 1 and message in proc.stderr and proc.stderr.count("\n") == 1
