"""Per-frame flow cost and rlc-vs-Womersley error from flow_frame_cost.csv, rlc_womersley.csv.

usage: plot_flow.py DATA_DIR OUT_DIR
"""
import os
import sys

from plot_common import PUBLISHED_DENSE_FRAME_S, PUBLISHED_DENSE_VESSELS, num, plt, read_csv, save

data, out = sys.argv[1], sys.argv[2]
rows = read_csv(f"{data}/flow_frame_cost.csv")
fig, a = plt.subplots(figsize=(6, 3.8))
for solver, style in (("dense_inverse", "s-"), ("superposition", "o-"), ("sparse", "^-")):
    pts = sorted((num(r["segments"]), num(r["frame_all_seconds"]), r["network"]) for r in rows if r["solver"] == solver)
    a.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=f"{solver} (all segments)")
    if solver == "superposition":
        pts = sorted((num(r["segments"]), num(r["frame_wire_seconds"])) for r in rows if r["solver"] == solver)
        a.loglog([p[0] for p in pts], [p[1] for p in pts], "o:", label="superposition (100 segments read)")
a.plot([PUBLISHED_DENSE_VESSELS], [PUBLISHED_DENSE_FRAME_S], "r*", ms=12, label="published: dense inverse, 2,477 vessels, 9 ms")
a.set_xlabel("network segments")
a.set_ylabel("seconds per flow frame")
a.legend(fontsize=7)
save(fig, f"{out}/flow_frame_cost.png")

rows = read_csv(f"{data}/rlc_womersley.csv")
fig, a = plt.subplots(figsize=(6, 3.8))
for alpha in sorted({r["alpha"] for r in rows}, key=float):
    for inert, style in (("womersley", "o-"), ("poiseuille", "x--")):
        pts = sorted((num(r["dt"]), num(r["amplitude_error"])) for r in rows if r["alpha"] == alpha and r["inertance"] == inert)
        a.loglog([p[0] for p in pts], [max(p[1], 1e-6) for p in pts], style, label=f"alpha {alpha}, L = {inert}")
    qs = [num(r["quasi_steady_amplitude_error"]) for r in rows if r["alpha"] == alpha][0]
    a.axhline(qs, color="gray", lw=0.6, ls=":")
a.set_xlabel("rlc time step [s]")
a.set_ylabel("| |Q/Qp| - Womersley | / Womersley")
a.set_title("rlc vs Womersley (dotted: quasi-steady Poiseuille error)", fontsize=9)
a.legend(fontsize=6, ncol=2)
save(fig, f"{out}/rlc_womersley.png")

path = f"{data}/flow_fem_work_precision.csv"
if os.path.exists(path):
    rows = read_csv(path)
    fig, a = plt.subplots(figsize=(6, 3.8))
    for model, style, label in (("network", "o-", "network (Poiseuille), over segment refinement"),
                                ("fem", "s-", "3D FEM (Stokes P2/P1), over mesh size")):
        pts = sorted((num(r["seconds"]), num(r["error"]), r["size"]) for r in rows if r["model"] == model)
        a.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=label)
        for s, e, n in pts:
            a.annotate(n, (s, e), fontsize=6, xytext=(2, 2), textcoords="offset points")
    a.set_xlabel("run time [s]")
    a.set_ylabel("outlet-flow error vs finest FEM (fraction of total flow)")
    a.set_title("Y bifurcation: network vs FEM (labels: segments / tetrahedra)", fontsize=9)
    a.legend(fontsize=7)
    save(fig, f"{out}/flow_fem_work_precision.png")
