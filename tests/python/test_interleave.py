"""bench/interleave.py: the rows it reads from each benchmark's output, and its ratios of two fake builds."""
import importlib.util
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("interleave", ROOT / "bench" / "interleave.py")
interleave = importlib.util.module_from_spec(spec)
spec.loader.exec_module(interleave)


def test_figures_reads_every_benchmarks_rows():
    text = "\n".join([
        "case             wall ms       M/s |    CPU ms       M/s",
        "rgl eval           84.08     12.47 |     84.04     12.48",
        "  cardboard | 0.95 | 1.02",
        "eval nearest     median    41.72 ms   25.13 M pairs/s   0.37 x coords time",
        "bivariate 64x32 uint8 log, bin centre, nearest lookup          6216 B  median    26.42 ms   39.69 M pairs/s",
        "  sample() (fine sampler), random wo: 2.50 M samples/s (median of 7, one core), 1.59 M/s one call at a "
        "time; eval() alone at the drawn pairs: 16.72 M pairs/s; the draw alone: 3.39 M/s one at a time, "
        "4.00 M/s in blocks  [1.3e+06]",
        "SIMD: avx2; pairs: 1048576; reps: 1; checksum 5984862.873",
    ])
    assert interleave.figures(text) == {
        ("rgl eval", "CPU ms"): 84.04,
        ("cardboard", "col1"): 0.95,
        ("cardboard", "col2"): 1.02,
        ("eval nearest", "ms"): 41.72,
        ("bivariate 64x32 uint8 log, bin centre, nearest lookup 6216 B", "ms"): 26.42,
        ("sample(), random wo", "ns"): 400.0,
        ("draw in blocks, random wo", "ns"): 250.0,
    }


def test_figures_reads_csv_rows_under_their_header():
    text = "\n".join([
        "file,spec,bytes,load_ms,eval_one_ns,eval_one_ratio",
        'a.bsdf,"svd:rank=8,dtype=f16",14944,0.84,21.5,1.10',
        'a.bsdf,"tabular:res=8x8x16",8000,0.50,30.0,0.90',
        "[12.5]",
    ])
    assert interleave.figures(text) == {
        ("a.bsdf svd:rank=8,dtype=f16", "load_ms"): 0.84,
        ("a.bsdf svd:rank=8,dtype=f16", "eval_one_ns"): 21.5,
        ("a.bsdf tabular:res=8x8x16", "load_ms"): 0.50,
        ("a.bsdf tabular:res=8x8x16", "eval_one_ns"): 30.0,
    }


def test_ratios_of_two_builds(tmp_path, monkeypatch, capsys):
    a, b = tmp_path / "a.sh", tmp_path / "b.sh"
    a.write_text("echo 'eval linear  median  30.0 ms'\n")
    b.write_text("echo 'eval linear  median  20.0 ms'\n")
    monkeypatch.setattr(sys, "argv", ["interleave.py", "--a", f"sh {a}", "--b", f"sh {b}", "--rounds", "3"])
    assert interleave.main() == 0
    row = next(line for line in capsys.readouterr().out.splitlines() if "eval linear" in line)
    assert row.split()[-2:] == ["1.500", "(1.500-1.500)"]
