"""The Neural-BRDF peer (Sztrajman et al. 2021) against brdfz on the shared RGL files, in both metrics.

    PYTHONPATH=build/python .venv/bin/python bench/nbrdf.py [--files F.bsdf ...] [--small SPEC]
                                                              [--budget E] [--directions N] [--csv OUT.csv]
    PYTHONPATH=build/python .venv/bin/python bench/nbrdf.py --sized [--files F.bsdf ...] [--csv OUT.csv]

For each RGL-EPFL file that ../shared/data/rgl-nbrdf/weights.npz has a fit of, the published 6-21-21-3
network (675 float32 parameters: 2,700 B) is evaluated with numpy on exactly the samples brdfz's metrics
take against the file (brdfz.metric_samples: the grid's bins, and direction pairs uniform in solid angle,
docs/metrics.md) and judged with brdfz.metrics_at. brdfz's side: the setting `--small` (at most the
network's bytes); what `compress --auto --max-error E --metric cos --over directions` picks from the
default candidates (E = --budget, 0.02), and the setting of at most 16 KiB it would take: its pick when
that is no larger, else the candidate of at most 16 KiB with the lowest error over directions. Each is
built from the file and judged with brdfz.metrics on the same samples. Prints one row per file
(cos_rmse_rel, %) and the medians; --csv writes the rows.

With --sized, only what `compress --auto --max-bytes B --metric cos --over directions` picks with B the
network's bytes (the most accurate default candidate that is no larger) against the network, over
directions and on the grid, counted separately on the tune and validate halves of the files (TUNE).

The network's input is the half vector rotated to φh = 0, (sin θh, 0, cos θh), and the difference
vector of wo in the half vector's frame (brdfz's wi is the file's incident direction; ../shared/data/README.md);
its output y gives f_r = max(exp(y) − 1, 0) per channel.
"""
import argparse
import csv
import os
import pathlib
import statistics
import sys

import numpy as np

import brdfz

SHARED = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data"
# The setting bench/README.md reports ("Neural-BRDF peer"); see docs/repr-specs.md.
SMALL = "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16"
MEDIUM_BYTES = 16 * 1024
# The half of the shared files defaults and constants are chosen on (bench/README.md); the rest validate.
TUNE = {"acrylic_felt_white", "cardboard", "cc_nothern_aurora", "colodur_azure_4e", "irid_flake_paint2", "paper_white",
        "satin_rosaline"}


def nbrdf_eval(weights, name, wi, wo):
    """f_r of the network `name` at pairs (wi, wo), (N, 3) arrays of unit vectors."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    theta_h = np.arccos(np.clip(h[:, 2], -1.0, 1.0))
    phi_h = np.arctan2(h[:, 1], h[:, 0])
    # wo rotated by -φh about z, then by -θh about y: its difference vector.
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    x, y, z = c * wo[:, 0] - s * wo[:, 1], s * wo[:, 0] + c * wo[:, 1], wo[:, 2]
    c, s = np.cos(-theta_h), np.sin(-theta_h)
    d = np.stack([c * x + s * z, y, -s * x + c * z], axis=1)
    hx = np.stack([np.sin(theta_h), np.zeros_like(theta_h), np.cos(theta_h)], axis=1)
    a = np.concatenate([hx, d], axis=1).astype(np.float32)
    a = np.maximum(a @ weights[f"{name}/W1"] + weights[f"{name}/b1"], 0)
    a = np.maximum(a @ weights[f"{name}/W2"] + weights[f"{name}/b2"], 0)
    y = (a @ weights[f"{name}/W3"] + weights[f"{name}/b3"]).astype(np.float64)
    return np.maximum(np.expm1(y), 0.0)


def nbrdf_bytes(weights, name):
    return sum(weights[f"{name}/{k}"].size for k in ("W1", "b1", "W2", "b2", "W3", "b3")) * 4


def fitted(files, names):
    """(name, loaded file) of each file the weights have a network of; the others named on stderr."""
    for path in files:
        name = path.name.removesuffix("_rgb.bsdf").removesuffix(".bsdf")
        if name not in names:
            print(f"{name}: no Neural-BRDF fit, skipped", file=sys.stderr)
            continue
        yield name, brdfz.load(path)


def sized(args, weights, names):
    """--sized: --auto --max-bytes (the network's bytes) against the network on the same samples."""
    header = ["file", "half", "nbrdf_bytes", "sized_bytes", "nbrdf_dirs", "sized_dirs", "nbrdf_grid", "sized_grid", "sized_spec"]
    print(" ".join(f"{h:>12}" for h in header[:-1]), header[-1])
    rows = []
    for name, ref in fitted(args.files, names):
        budget = nbrdf_bytes(weights, name)
        picked = brdfz.compress(ref, auto=True, max_bytes=budget, metric="cos", over="directions",
                                directions=args.directions, threads=args.threads, report=True)
        row = {"file": name, "half": "tune" if name in TUNE else "validate", "nbrdf_bytes": budget,
               "sized_bytes": picked.brdf.nbytes, "sized_spec": picked.candidates[picked.chosen].spec}
        for over, key in (("directions", "dirs"), ("grid", "grid")):
            opts = dict(over=over, directions=args.directions, threads=args.threads)
            wi, wo, f = brdfz.metric_samples(ref, **opts)
            row[f"nbrdf_{key}"] = brdfz.metrics_at(wi, f, nbrdf_eval(weights, name, wi, wo)).cos_rmse_rel.mean
            row[f"sized_{key}"] = brdfz.metrics(ref, picked.brdf, **opts).cos_rmse_rel.mean
        rows.append(row)
        print(" ".join(f"{row[h]:>12}" if isinstance(row[h], (str, int)) else f"{100 * row[h]:>11.2f}%"
                       for h in header[:-1]), row["sized_spec"], flush=True)
    if not rows:
        sys.exit("nbrdf: no file had a fit")
    for half in ("tune", "validate"):
        part = [r for r in rows if r["half"] == half]
        wins = {k: sum(r[f"sized_{k}"] < r[f"nbrdf_{k}"] for r in part) for k in ("dirs", "grid")}
        print(f"{half}: --auto --max-bytes (network's bytes) below the network on {wins['dirs']} of {len(part)} files "
              f"over directions, {wins['grid']} of {len(part)} on the grid")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=header)
            w.writeheader()
            w.writerows(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--files", nargs="*", type=pathlib.Path,
                    default=sorted((SHARED / "rgl").glob("*.bsdf")) if (SHARED / "rgl").is_dir() else [])
    ap.add_argument("--weights", type=pathlib.Path, default=SHARED / "rgl-nbrdf" / "weights.npz")
    ap.add_argument("--small", default=SMALL, help="brdfz setting of at most the network's bytes")
    ap.add_argument("--budget", type=float, default=0.02, help="--auto's budget (cos_rmse_rel over directions)")
    ap.add_argument("--directions", type=int, default=1 << 18)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--csv", type=pathlib.Path)
    ap.add_argument("--sized", action="store_true", help="only --auto --max-bytes at the network's bytes")
    args = ap.parse_args()
    if not args.files or not args.weights.exists():
        sys.exit(f"nbrdf: no RGL files or no weights ({SHARED}): nothing to compare")
    weights = np.load(args.weights)
    names = {k.split("/")[0] for k in weights.files}
    if args.sized:
        return sized(args, weights, names)
    rows = []
    header = ["file", "nbrdf_bytes", "small_bytes", "k16_bytes", "auto_bytes"] + [
        f"{who}_{over}" for over in ("grid", "dirs") for who in ("nbrdf", "small", "k16", "auto")] + [
        "auto_spec", "k16_spec"]
    first_error = header.index("nbrdf_grid")
    print(" ".join(f"{h:>12}" for h in header[:-1]), header[-1])
    for name, ref in fitted(args.files, names):
        small = brdfz.compress(ref, args.small, threads=args.threads)
        try:
            picked = brdfz.compress(ref, auto=True, max_error=args.budget, metric="cos", over="directions",
                                    directions=args.directions, threads=args.threads, report=True)
            auto = picked.brdf
            auto_spec = picked.candidates[picked.chosen].spec
        except ValueError as e:  # no candidate within the budget: the report names the best
            picked = e.selection
            best = min((c for c in picked.candidates if c.error == c.error), key=lambda c: c.error)
            auto = brdfz.compress(ref, best.spec, threads=args.threads)
            auto_spec = f"(none within {args.budget:g}; best) {best.spec}"
        if auto.nbytes <= MEDIUM_BYTES:
            k16, k16_spec = auto, auto_spec
        else:  # the candidates tried up to the pick include every one of at most 16 KiB
            best = min((c for c in picked.candidates if c.bytes <= MEDIUM_BYTES and c.error == c.error),
                       key=lambda c: c.error)
            k16, k16_spec = brdfz.compress(ref, best.spec, threads=args.threads), best.spec
        row = {"file": name, "nbrdf_bytes": nbrdf_bytes(weights, name), "small_bytes": small.nbytes,
               "k16_bytes": k16.nbytes, "auto_bytes": auto.nbytes, "auto_spec": auto_spec, "k16_spec": k16_spec}
        for over in ("grid", "directions"):
            opts = dict(over=over, directions=args.directions, threads=args.threads)
            wi, wo, f = brdfz.metric_samples(ref, **opts)
            key = "grid" if over == "grid" else "dirs"
            row[f"nbrdf_{key}"] = brdfz.metrics_at(wi, f, nbrdf_eval(weights, name, wi, wo)).cos_rmse_rel.mean
            row[f"small_{key}"] = brdfz.metrics(ref, small, **opts).cos_rmse_rel.mean
            row[f"k16_{key}"] = brdfz.metrics(ref, k16, **opts).cos_rmse_rel.mean
            row[f"auto_{key}"] = brdfz.metrics(ref, auto, **opts).cos_rmse_rel.mean
        rows.append(row)
        print(" ".join(f"{row[h]:>12}" if isinstance(row[h], (str, int)) else f"{100 * row[h]:>11.2f}%"
                       for h in header[:-2]), row["auto_spec"], "|", row["k16_spec"], flush=True)
    if not rows:
        sys.exit("nbrdf: no file had a fit")
    med = {h: statistics.median(r[h] for r in rows) for h in header[first_error:-2]}
    print(" ".join([f"{'median':>12}"] + [" " * 12] * (first_error - 1) +
                   [f"{100 * med[h]:>11.2f}%" for h in header[first_error:-2]]))
    for who in ("small", "k16"):
        wins = {k: sum(r[f"{who}_{k}"] < r[f"nbrdf_{k}"] for r in rows) for k in ("grid", "dirs")}
        print(f"{who} below the network: {wins['grid']} of {len(rows)} files on the grid, "
              f"{wins['dirs']} of {len(rows)} over directions")
    met = [r["file"] for r in rows if r["auto_bytes"] <= MEDIUM_BYTES and r["auto_dirs"] <= args.budget]
    print(f"--auto within {args.budget:g} over directions at <= {MEDIUM_BYTES} B: {len(met)} of {len(rows)} files")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=header)
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
