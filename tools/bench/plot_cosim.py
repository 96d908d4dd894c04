"""Co-simulation work-precision and feature cost from cosim_work_precision.csv, feature_cost.csv.

usage: plot_cosim.py DATA_DIR OUT_DIR
"""
import sys

from plot_common import PUBLISHED_FRAME_S, num, plt, read_csv, save

data, out = sys.argv[1], sys.argv[2]
rows = read_csv(f"{data}/cosim_work_precision.csv")
ref = rows[0]
fig, a = plt.subplots(figsize=(6, 3.8))
for seg in sorted({r["segment_length"] for r in rows[1:]}, key=float):
    pts = sorted((num(r["seconds"]), num(r["rms_error"]), num(r["dt"])) for r in rows[1:] if r["segment_length"] == seg)
    a.loglog([p[0] for p in pts], [max(p[1], 1e-7) for p in pts], "o-", label=f"segment {float(seg)*1e3:g} mm")
    for s, e, dt in pts:
        a.annotate(f"{dt*1e3:g} ms", (s, max(e, 1e-7)), fontsize=6, xytext=(2, 2), textcoords="offset points")
a.set_xlabel("run time [s]")
a.set_ylabel("tip-trace RMS distance to reference [m]")
a.set_title(f"aortic arch, flow on; reference dt {float(ref['dt'])*1e3:g} ms, "
            f"segment {float(ref['segment_length'])*1e3:g} mm ({num(ref['seconds']):.1f} s)", fontsize=8)
a.legend(fontsize=7)
save(fig, f"{out}/cosim_work_precision.png")

rows = read_csv(f"{data}/feature_cost.csv")
phases = ["flow", "rod", "contact", "coupling", "output"]
fig, a = plt.subplots(figsize=(7, 3.8))
bottom = [0.0] * len(rows)
for ph in phases:
    vals = [1e3 * num(r[ph]) / max(num(r["steps"]), 1) for r in rows]
    a.bar([r["variant"] for r in rows], vals, bottom=bottom, label=ph)
    bottom = [b + v for b, v in zip(bottom, vals)]
a.axhline(1e3 * PUBLISHED_FRAME_S, color="r", ls="--", label="published frame 24.6 ms")
a.set_yscale("log")
a.set_ylabel("ms per step (phases stacked)")
a.tick_params(axis="x", labelsize=7, rotation=20)
a.legend(fontsize=7)
save(fig, f"{out}/feature_cost.png")
