#!/usr/bin/env python3
"""Plot pressure and flow waveforms per vessel from a flowire vessels.csv (PNG).

usage: plot_vessels.py DIR/vessels.csv OUT.png [VESSEL ...]

vessels.csv is what `flowire run MODEL.yaml` writes for an openBF model (name,time,flow_in,
flow_out,pressure_in,pressure_out; SI). The figure draws, for each vessel named (default: the
first vessel, the one fed by the inlet, and up to five of the model's outlets spread along it),
the inlet pressure in mmHg over the last cycle on top and the inlet flow in mL/s below: the
waveforms along the aorta and at the periphery, as the 1D papers draw them.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MMHG = 133.322387415


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    by = {}
    with open(argv[1], newline="") as f:
        for r in csv.DictReader(f):
            by.setdefault(r["name"], []).append(r)
    if not by:
        print(f"plot_vessels.py: {argv[1]}: no rows", file=sys.stderr)
        return 2
    names = argv[3:]
    if not names:
        order = list(by)
        step = max(1, len(order) // 5)
        names = order[:1] + order[step::step][:5]
    unknown = [n for n in names if n not in by]
    if unknown:
        print(f"plot_vessels.py: {argv[1]}: no vessel named {', '.join(unknown)}", file=sys.stderr)
        return 2
    fig, (ax_p, ax_q) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for n in names:
        t = [float(r["time"]) for r in by[n]]
        ax_p.plot(t, [float(r["pressure_in"]) / MMHG for r in by[n]], label=n)
        ax_q.plot(t, [float(r["flow_in"]) * 1e6 for r in by[n]], label=n)
    ax_p.set_ylabel("pressure at the vessel's inlet (mmHg)")
    ax_q.set_ylabel("flow at the vessel's inlet (mL/s)")
    ax_q.set_xlabel("time in the last cycle (s)")
    ax_p.legend(fontsize=8)
    ax_p.grid(alpha=0.3)
    ax_q.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
