#!/usr/bin/env python3
"""Plot guidewire tip traces and their distance by inserted length (PNG).

usage: plot_traces.py OUT.png LABEL=trace.csv [LABEL=trace.csv ...] [--compare compare.csv]
                      [--views H:V,H:V]

Each trace is a flowire tip_trace.csv (time,inserted_length,x,y,z). The figure shows the
traces seen from the front (x-z) and from the side (y-z), or the two views given by
--views (columns of the trace, e.g. x:y,time:y for a tip that moves in the x-y plane),
and, if a comparison table from `flowire compare --out` is given, the RMS distance by
inserted length (the published Table 2 layout).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in ("time", "inserted_length", "x", "y", "z")}


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out = argv[1]
    traces, compare = [], None
    views = [("x", "z"), ("y", "z")]
    args = argv[2:]
    i = 0
    while i < len(args):
        if args[i] == "--views":
            views = [tuple(v.split(":")) for v in args[i + 1].split(",")]
            i += 2
            continue
        if args[i] == "--compare":
            compare = args[i + 1]
            i += 2
            continue
        label, _, path = args[i].partition("=")
        traces.append((label, read(path)))
        i += 1
    ncols = 3 if compare else 2
    fig, axes = plt.subplots(1, ncols, figsize=(5 * ncols, 5))
    def scale(key, values):
        return values if key == "time" else [v * 1e3 for v in values]

    def unit(key):
        return "time (s)" if key == "time" else f"{key} (mm)"

    for label, t in traces:
        for ax, (h, v) in zip(axes, views):
            ax.plot(scale(h, t[h]), scale(v, t[v]), label=label)
    for ax, (h, v) in zip(axes, views):
        ax.set_xlabel(unit(h))
        ax.set_ylabel(unit(v))
        if "time" not in (h, v):
            ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    default = views == [("x", "z"), ("y", "z")]
    axes[0].set_title("tip trace, front" if default else f"tip trace, {views[0][0]}-{views[0][1]}")
    axes[1].set_title("tip trace, side" if default else f"tip trace, {views[1][0]}-{views[1][1]}")
    axes[0].legend(fontsize=8)
    if compare:
        with open(compare, newline="") as f:
            rows = list(csv.DictReader(f))
        L = [float(r["inserted_length"]) * 1e3 for r in rows]
        axes[2].plot(L, [float(r["rms"]) * 1e3 for r in rows], "o-", label="RMS (1/n)")
        axes[2].plot(L, [float(r["rms_published"]) * 1e3 for r in rows], "s--", label="RMS (1/2, eq. 11)")
        axes[2].set_xlabel("inserted length (mm)")
        axes[2].set_ylabel("distance (mm)")
        axes[2].set_title("trace distance")
        axes[2].grid(True, alpha=0.3)
        axes[2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110, format="png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
