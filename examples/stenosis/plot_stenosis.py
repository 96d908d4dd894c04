#!/usr/bin/env python3
"""The pressure along a single vessel: the 3D solution's section-mean pressure (fem_compare.csv
of a `flowire run examples/stenosis/scene.yaml`, or of examples/bend, examples/entrance) against the
network's of each run given, each labelled by its flow.losses (summary.json), with the lumen's
radius below.
Usage: plot_stenosis.py OUT_PNG RUN_DIR [RUN_DIR ...]   (the 3D curve from the first run)."""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(run):
    rows = list(csv.DictReader(open(os.path.join(run, "fem_compare.csv"))))
    col = {k: [float(r[k]) for r in rows] for k in ("s", "pressure_network", "pressure_fem", "radius_network")}
    flow = json.load(open(os.path.join(run, "summary.json"))).get("flow", {})
    losses = flow.get("losses", {})
    models = [losses[k]["model"] for k in ("stenosis", "curvature", "entrance") if k in losses]
    label = "network, " + (" + ".join(models) if models else "Poiseuille")
    return col, label


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out, runs = sys.argv[1], sys.argv[2:]
    fig, (ax, axr) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    first, _ = read(runs[0])
    s_mm = [1e3 * v for v in first["s"]]
    ax.plot(s_mm, first["pressure_fem"], "k-", lw=2, label="3D Navier–Stokes (section mean)")
    for run in runs:
        col, label = read(run)
        ax.plot([1e3 * v for v in col["s"]], col["pressure_network"], "--", lw=1.5, label=label)
    ax.set_ylabel("pressure above the outlet [Pa]")
    ax.legend()
    ax.grid(alpha=0.3)
    axr.plot(s_mm, [1e3 * v for v in first["radius_network"]], "k-")
    axr.set_ylabel("radius [mm]")
    axr.set_xlabel("distance from the inlet [mm]")
    axr.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
