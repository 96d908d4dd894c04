#!/usr/bin/env python3
"""Markdown tables from a fem_compare.csv (flowire run with fem:): every sample point with the
network's and the FEM's pressure and flow and their relative differences, then, per branch,
the FEM/network pressure drop between the first and last samples away from junctions beside
the Poiseuille prediction of that ratio from the two radii, mean((r_network/r_fem)^4), where
r_fem = sqrt(A/pi) of the FEM cross-section.

    python3 flow/fem/scripts/fem_lumen_table.py OUT/fem_compare.csv
"""
import csv
import math
import sys


def main(path):
    rows = list(csv.DictReader(open(path)))
    f = lambda r, k: float(r[k])
    print("| point | branch | s (mm) | p network (Pa) | p FEM (Pa) | rel. diff | diff / drop | Q network (mL/s) "
          "| Q FEM (mL/s) | rel. diff Q | r network / FEM (mm) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for i, r in enumerate(rows, 1):
        star = "*" if r["near_junction"] == "1" else ""
        qf = f(r, "flow_fem")
        qcell = "—" if math.isnan(qf) else f"{qf * 1e6:.2f}"
        dq = "—" if math.isnan(qf) or star else f"{100 * f(r, 'rel_diff_flow'):+.1f}%"
        print(f"| {i}{star} | {r['branch']} | {f(r, 's') * 1e3:.1f} | {f(r, 'pressure_network'):.3f} "
              f"| {f(r, 'pressure_fem'):.3f} | {100 * f(r, 'rel_diff'):+.1f}% | {100 * f(r, 'rel_diff_drop'):+.1f}% "
              f"| {f(r, 'flow_network') * 1e6:.2f} | {qcell} | {dq} "
              f"| {f(r, 'radius_network') * 1e3:.2f} / {f(r, 'radius_fem') * 1e3:.2f} |")
    print()
    print("| branch | samples away from junctions | drop FEM / network | mean (r_network / r_fem)^4 |")
    print("|---|---|---|---|")
    branches = []
    for r in rows:
        if r["branch"] not in branches:
            branches.append(r["branch"])
    for b in branches:
        pts = [r for r in rows if r["branch"] == b and r["near_junction"] == "0" and not math.isnan(f(r, "radius_fem"))]
        if len(pts) < 2:
            continue
        dn = f(pts[0], "pressure_network") - f(pts[-1], "pressure_network")
        df = f(pts[0], "pressure_fem") - f(pts[-1], "pressure_fem")
        ratio = sum((f(r, "radius_network") / f(r, "radius_fem")) ** 4 for r in pts) / len(pts)
        print(f"| {b} | {len(pts)} | {df / dn:.3f} | {ratio:.3f} |")


if __name__ == "__main__":
    main(sys.argv[1])
