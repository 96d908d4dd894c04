"""Rod work-precision and step cost from rod_work_precision.csv.

usage: plot_rod.py DATA_DIR OUT_DIR
"""
import math
import sys

from plot_common import PUBLISHED_ROD_STEP_S, num, plt, read_csv, save

data, out = sys.argv[1], sys.argv[2]
rows = read_csv(f"{data}/rod_work_precision.csv")

fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6))
colours = {}
for case, integ in sorted({(r["case"], r["integrator"]) for r in rows if r["integrator"].startswith("static")}):
    pts = [(num(r["seconds"]), num(r["error"]), r["segments"]) for r in rows if r["case"] == case and r["integrator"] == integ]
    pts = [p for p in pts if math.isfinite(p[1]) and p[1] > 0]
    adaptive = integ == "static_adaptive"
    label = case.replace("cantilever_", "elastica ") + (" adaptive" if adaptive else "")
    line, = a.loglog([p[0] for p in pts], [p[1] for p in pts], "s" if adaptive else "o-", label=label,
                     color=colours.get(case), mfc="none" if adaptive else None)
    colours[case] = line.get_color()
    for s, e, n in pts[::2]:
        a.annotate(n, (s, e), fontsize=6, xytext=(2, 2), textcoords="offset points")
a.set_xlabel("run time of the static solve [s]")
a.set_ylabel("error / L (tip) or |P - Pcr|/Pcr")
a.set_title("statics: error vs run time (labels: segments)", fontsize=9)
a.legend(fontsize=7)
for integ in ("implicit_euler", "implicit_midpoint"):
    pts = [(num(r["seconds"]), num(r["error"])) for r in rows if r["case"] == "frequency" and r["integrator"] == integ]
    pts = [p for p in pts if math.isfinite(p[1]) and p[1] > 0]
    b.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=integ)
b.set_xlabel("run time of 3 periods [s] (dt = T/5 ... T/320)")
b.set_ylabel("|T - T1| / T1")
b.set_title("first cantilever frequency, 50 segments", fontsize=9)
b.legend(fontsize=7)
save(fig, f"{out}/rod_work_precision.png")

fig, a = plt.subplots(figsize=(5.5, 3.6))
for integ in ("implicit_euler", "implicit_midpoint"):
    pts = [(num(r["segments"]), num(r["seconds"])) for r in rows if r["case"] == "step_cost" and r["integrator"] == integ]
    a.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=integ)
a.axhspan(*PUBLISHED_ROD_STEP_S, color="tab:red", alpha=0.15, label="published rods: 5-36 ms/step")
a.plot([1700], [1e-3], "k*", ms=10, label="aim: 1 ms at 1,700 vertices")
a.set_xlabel("segments (1 mm each)")
a.set_ylabel("seconds per implicit step (dt = 1 ms)")
a.legend(fontsize=7)
save(fig, f"{out}/rod_step_cost.png")
