"""Charts of the stability study's CSV (bench/stability): a method × material heat map of
cos_rmse_rel, each cell marked with its failure signs, and the same as a Markdown table.

    python -m brdfz.stability_charts stability.csv [--out DIR]

Writes DIR/stability_heatmap.png and DIR/table.md (default DIR: the CSV's folder). Cells: colour =
cos_rmse_rel (log scale, the value printed); a grey cell with "✗" = the build failed; letters = the
study's flags: B error blow-up, V bad values, G grazing artefacts, S sampler worse than cosine, P the
fit's poor-fit warning (converged, but the model misses the data), F the fit's status
(no_convergence, hit_bounds). The table prints each cell's cos_rmse_rel ("fails" when the build
failed) followed by its flags in words.
"""
from __future__ import annotations

import argparse
import csv
import math
import pathlib
import sys
from typing import Dict, List, Optional, Sequence

import numpy as np

COLUMNS = ["material", "class", "repr", "status", "bytes", "cos_rmse_rel", "log_rmse", "grazing_ratio",
           "sampler_variance_ratio", "bad_values", "eval_pairs_per_s", "build_s", "flags"]
FLAG_LETTERS = {"error blow-up": "B", "bad values": "V", "grazing artefacts": "G", "sampler worse than cosine": "S",
                "poor fit": "P"}


def flag_letters(flags: str) -> str:
    """The cell's marks for a row's flags ("; "-separated); flags not listed above are fit statuses."""
    out = ""
    for f in filter(None, (f.strip() for f in flags.split(";"))):
        if f != "failed":
            out += FLAG_LETTERS.get(f, "F")
    return "".join(sorted(set(out), key=out.index))


def read_rows(csv_path: pathlib.Path) -> List[Dict[str, str]]:
    with open(csv_path, newline="") as f:
        reader = csv.DictReader(f)
        missing = set(COLUMNS) - set(reader.fieldnames or [])
        if missing:
            raise ValueError(f"{csv_path}: not a stability CSV (no column {', '.join(sorted(missing))})")
        return list(reader)


def markdown_table(rows: Sequence[Dict[str, str]]) -> str:
    """Methods down, materials across: cos_rmse_rel with the flags ("fails" for a failed build)."""
    methods = list(dict.fromkeys(r["repr"] for r in rows))
    materials = list(dict.fromkeys(r["material"] for r in rows))
    cells = {(r["repr"], r["material"]): r for r in rows}
    lines = ["| method | " + " | ".join(materials) + " |", "|---|" + "---|" * len(materials)]
    for m in methods:
        out = []
        for name in materials:
            r = cells.get((m, name))
            if r is None:
                out.append("")
                continue
            cell = "fails" if r["status"].startswith("error") else r["cos_rmse_rel"]
            flags = [f.strip() for f in r["flags"].split(";") if f.strip() and f.strip() != "failed"]
            out.append(cell + "".join(f" ⚠ {f}" for f in flags))
        lines.append(f"| `{m}` | " + " | ".join(out) + " |")
    return "\n".join(lines) + "\n"


def heatmap(csv_path: pathlib.Path, png: pathlib.Path) -> pathlib.Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt

    rows = read_rows(csv_path)
    methods = list(dict.fromkeys(r["repr"] for r in rows))
    materials = list(dict.fromkeys(r["material"] for r in rows))
    value = np.full((len(methods), len(materials)), np.nan)
    marks = [["" for _ in materials] for _ in methods]
    failed = np.zeros(value.shape, dtype=bool)
    for r in rows:
        i, j = methods.index(r["repr"]), materials.index(r["material"])
        if r["status"].startswith("error"):
            failed[i, j] = True
            continue
        value[i, j] = float(r["cos_rmse_rel"]) if r["cos_rmse_rel"] else math.nan
        marks[i][j] = flag_letters(r["flags"])
    finite = value[np.isfinite(value) & (value > 0)]
    norm = mcolors.LogNorm(vmin=max(finite.min(), 1e-4), vmax=max(finite.max(), 1e-3)) if finite.size else None

    fig, ax = plt.subplots(figsize=(1.0 * len(materials) + 4, 0.42 * len(methods) + 2))
    cmap = plt.get_cmap("viridis").with_extremes(bad="lightgrey")
    im = ax.imshow(np.where(value > 0, value, np.nan), cmap=cmap, norm=norm, aspect="auto")
    for i in range(len(methods)):
        for j in range(len(materials)):
            if failed[i, j]:
                text, colour = "✗", "black"
            elif math.isnan(value[i, j]):
                continue
            else:
                text = f"{value[i, j]:.2g}" + (f"\n{marks[i][j]}" if marks[i][j] else "")
                dark = norm is not None and value[i, j] > 0 and norm(value[i, j]) < 0.6
                colour = "white" if dark else "black"
            ax.text(j, i, text, ha="center", va="center", fontsize=6.5, color=colour,
                    fontweight="bold" if marks[i][j] or failed[i, j] else "normal")
    ax.set_xticks(range(len(materials)), materials, rotation=40, ha="right", fontsize=8)
    ax.set_yticks(range(len(methods)), methods, fontsize=8)
    ax.set_title("stability: cos_rmse_rel per method and material\n✗ failed  B blow-up  V bad values\n"
                 "G grazing artefacts  S sampler worse than cosine  P poor fit  F fit status", fontsize=9)
    fig.colorbar(im, ax=ax, label="cos_rmse_rel (log)")
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)
    return png


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m brdfz.stability_charts", description=__doc__.split("\n\n")[0])
    p.add_argument("csv", help="the CSV bench/stability wrote")
    p.add_argument("--out", help="output folder (default: the CSV's)")
    args = p.parse_args(argv)
    src = pathlib.Path(args.csv)
    out = pathlib.Path(args.out) if args.out else src.parent
    out.mkdir(parents=True, exist_ok=True)
    table = out / "table.md"
    table.write_text(markdown_table(read_rows(src)))
    print(f"wrote {heatmap(src, out / 'stability_heatmap.png')} and {table}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
