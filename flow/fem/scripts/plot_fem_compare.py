#!/usr/bin/env python3
"""Plot network vs FEM pressure along the path from the inlet.

Usage: plot_fem_compare.py fem_compare.csv out.png
Reads the columns branch, path_distance, pressure_network, pressure_fem (written by
flowire's FEM comparison) and draws one colour per branch: the network model as a
line, the FEM cross-section means as markers.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    rows = {}
    with open(argv[1], newline="") as f:
        for r in csv.DictReader(f):
            rows.setdefault(r["branch"], []).append(r)
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=120)
    for i, (name, pts) in enumerate(rows.items()):
        pts.sort(key=lambda r: float(r["path_distance"]))
        d = [1e3 * float(r["path_distance"]) for r in pts]
        pn = [1e-3 * float(r["pressure_network"]) for r in pts]
        pf = [1e-3 * float(r["pressure_fem"]) for r in pts]
        colour = "C%d" % (i % 10)
        ax.plot(d, pn, "-", color=colour, label="%s network" % name)
        ax.plot(d, pf, "o", color=colour, mfc="none", label="%s FEM" % name)
    ax.set_xlabel("distance from the inlet along the network (mm)")
    ax.set_ylabel("pressure (kPa)")
    ax.set_title("Network model vs 3D finite elements")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(argv[2], format="png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
