"""The benchmark's charts read at their default size (point labels inside their panels, tick labels
apart), its render error images on one scale that tells representations apart, and python -m
brdfz.bench's one-line answers before any work: matplotlib missing, no materials found."""
import json
import sys

import numpy as np
import pytest

from conftest import import_brdfz

brdfz = import_brdfz()
matplotlib = pytest.importorskip("matplotlib", reason="matplotlib is not installed (scripts/setup-deps)")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402

from brdfz import bench, report  # noqa: E402

LONG = ["tabular:res=90x90x180,dtype=u8log,symmetry=none", "svd:rank=8,space=log,symmetry=bilateral",
        "bivariate:res=64x64,dtype=f16", "analytic:lambert+ggx+ggx", "nmf:rank=4,symmetry=none", "pca:components=8"]


def rows():
    """Two materials, every setting on the Pareto front, eval speeds within one decade (where
    matplotlib labels the minor ticks of a log axis) and errors over three."""
    out = []
    for m, name in enumerate(["paper_white_rgb", "ilm_l3_37_metallic_rgb"]):
        for k, spec in enumerate(LONG):
            out.append({"material": name, "spec": spec, "status": "ok", "bytes": 2000 * 3 ** k,
                        "cos_rmse_rel": 0.3 / 3.1 ** k * (1 + m), "cos_rmse": 0.01, "log_rmse": 0.1, "cbrt_rmse": 0.1,
                        "eval_rate": 9e6 - 1.2e6 * k, "build_seconds": 1.0})
    return out


@pytest.fixture
def drawn(monkeypatch):
    """The figures report's charts draw, laid out and drawn as saved, kept open."""
    figures = []
    finish = report._finish

    def keep(fig, axes, path):
        finish(fig, axes, path)
        FigureCanvasAgg(fig).draw()  # closing the figure left it without a canvas
        figures.append(fig)

    monkeypatch.setattr(report, "_finish", keep)
    yield figures
    plt.close("all")


def inside(box, outer, slack=1.0):
    return (box.x0 >= outer.x0 - slack and box.x1 <= outer.x1 + slack and box.y0 >= outer.y0 - slack
            and box.y1 <= outer.y1 + slack)


def overlapping(boxes):
    return [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:] if a.overlaps(b)]


def check_readable(fig):
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        frame = ax.get_window_extent(renderer)
        labels = [t for t in ax.texts if t.get_visible()]
        assert labels, "no point labels drawn"
        for t in labels:
            assert inside(t.get_window_extent(renderer), frame), f"label {t.get_text()!r} spills out of its panel"
        for axis in (ax.xaxis, ax.yaxis):
            ticks = [t.get_window_extent(renderer) for t in axis.get_ticklabels(which="both")
                     if t.get_visible() and t.get_text()]
            assert len(ticks) >= 2, "an axis with fewer than two tick labels"
            assert not overlapping(ticks), f"overlapping tick labels on {ax.get_title()}"


@pytest.mark.parametrize("x, y", [("bytes", "cos_rmse_rel"), ("eval_rate", "cos_rmse_rel")])
def test_tradeoff_charts_are_readable(drawn, tmp_path, x, y):
    report.chart_tradeoff(rows(), x, y, tmp_path / "chart.png", maximize_x=x == "eval_rate")
    check_readable(drawn[0])


@pytest.mark.parametrize("x", ["bytes", "eval_rate"])
def test_auto_charts_are_readable(drawn, tmp_path, x):
    r = rows()
    auto = report.budget_choice(r, [0.02, 0.05, 0.2])
    assert sum(bool(a["chosen"]) for a in auto) >= 4
    report.chart_auto(r, auto, x, tmp_path / "auto.png")
    check_readable(drawn[0])


def test_render_error_images_tell_representations_apart(tmp_path, monkeypatch):
    def lambert(name, scale):
        path = tmp_path / f"{name}.json"
        params = {f"lambert.rho_{c}": 0.5 * scale for c in "rgb"}
        path.write_text(json.dumps({"format": "brdfz-analytic", "version": 1, "model": "lambert", "parameters": params}))
        return brdfz.load(path)

    monkeypatch.setattr(plt, "close", lambda *args: None)
    reps = [{"spec": "close", "bytes": 10, "cos_rmse_rel": 0.02}, {"spec": "far", "bytes": 10, "cos_rmse_rel": 0.4}]
    report.render_material("grey", lambert("ref", 1.0), reps, [lambert("close", 1.02), lambert("far", 1.4)],
                           tmp_path / "r.png", 32, 4)
    fig = plt.gcf()
    images = [ax.images[0] for ax in fig.axes[len(reps) + 2:2 * len(reps) + 2]]
    close, far = (np.asarray(im.get_array()) for im in images)
    vmax = images[0].norm.vmax
    assert images[1].norm.vmax == vmax  # one scale
    # The poorer representation spans the scale without saturating it, and the better one reads 20x
    # darker (a fixed ×10 gain saturated both).
    assert np.mean(far >= vmax) < 0.05 and np.percentile(far[far > 0], 99) == pytest.approx(vmax)
    assert np.percentile(close[close > 0], 99) < vmax / 10
    assert any(a.get_label() == "<colorbar>" for a in fig.axes)
    plt.close("all")


def test_bench_says_which_extra_to_install_before_any_work(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert bench.main(["--out", str(tmp_path / "out"), "--materials", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'brdfz[bench]'" in err
    assert not (tmp_path / "out").exists()


def test_bench_without_materials_says_where_it_looked(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("BRDFZ_MERL_DIR", raising=False)
    with pytest.raises(SystemExit) as e:
        bench.main(["--out", "out"])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert str((tmp_path / "../shared/data/rgl").resolve()) in err and str(tmp_path / "build/merl-tables") in err
    assert "--materials" in err and not (tmp_path / "out").exists()
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(SystemExit):
        bench.main(["--out", "out", "--materials", str(empty)])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"no materials in {empty}" in err and ".bsdf" in err
