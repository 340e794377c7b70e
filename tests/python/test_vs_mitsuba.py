"""bench/vs_mitsuba.py on one shared RGL file with a small representation and few pairs: it prints the
five ratios of issue 23's table as positive finite numbers, and names each side's SIMD width."""
import math
import os
import re
import subprocess
import sys

import pytest

from conftest import REPO, import_brdfz

brdfz = import_brdfz()
mi = pytest.importorskip("mitsuba")


def test_vs_mitsuba_prints_the_five_ratios(rgl_files):
    env = dict(os.environ)
    run = subprocess.run([sys.executable, str(REPO / "bench" / "vs_mitsuba.py"), str(rgl_files[0]),
                          "--spec", "tabular:res=8x8x16", "--pairs", "20000", "--reps", "5", "--render-reps", "5"],
                         capture_output=True, text=True, timeout=600, env=env)
    assert run.returncode == 0, run.stderr
    out = run.stdout
    assert re.search(rf"SIMD: brdfz {brdfz.simd()} .*Mitsuba llvm_ad_rgb, (4|8|16) float lanes", out), out
    ratios = re.findall(r"^  (brdfz RGL|representation|render time).*?\s(\d+\.\d+)\s+[≥≤]", out, re.M)
    assert len(ratios) == 5, out
    assert all(math.isfinite(float(r)) and float(r) > 0 for _, r in ratios)
