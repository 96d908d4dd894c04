#!/usr/bin/env python3
"""The entrance table of docs/flow-losses.md from runs of examples/entrance/scene.yaml.

  /usr/bin/python3 examples/entrance/table.py OUTDIR [OUTDIR ...]

For each run: Re (the FEM's own figure), the FEM's inlet pressure (the cross-section mean, the
whole drop: the outlet is at 0 Pa), the network's, and the largest |FEM - network| over the
drop at the sample points (every 0.5 mm), and the same from x = 2 mm on (past the inlet's
singular corner, where the flat profile meets the wall).
"""
import csv
import json
import os
import sys


def main():
    print("| run | Re | FEM inlet (Pa) | network inlet (Pa) | network - FEM | largest diff / drop | from x = 2 mm |")
    print("|---|---|---|---|---|---|---|")
    for d in sys.argv[1:]:
        with open(os.path.join(d, "summary.json")) as f:
            s = json.load(f)
        with open(os.path.join(d, "fem_compare.csv")) as f:
            rows = list(csv.DictReader(f))
        pn = [float(r["pressure_network"]) for r in rows]
        pf = [float(r["pressure_fem"]) for r in rows]
        x = [float(r["s"]) for r in rows]
        drop = pn[0] - pn[-1]
        worst = max(abs(a - b) for a, b in zip(pn, pf)) / drop
        past = max(abs(a - b) for a, b, xx in zip(pn, pf, x) if xx >= 2e-3) / drop
        print(f"| {os.path.basename(d.rstrip('/'))} | {s['fem']['reynolds']:.0f} | {pf[0]:.3f} | {pn[0]:.3f} | "
              f"{(pn[0] - pf[0]) / pf[0]:+.2%} | {worst:.2%} | {past:.2%} |")


if __name__ == "__main__":
    main()
