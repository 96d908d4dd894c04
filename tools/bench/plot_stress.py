"""Stress heat maps from stress.csv: pass fraction over dt x stiffness (all other axes
pooled) and over flow amplitude x friction.

usage: plot_stress.py DATA_DIR OUT_DIR
"""
import sys

import numpy as np

from plot_common import num, plt, read_csv, save

data, out = sys.argv[1], sys.argv[2]
rows = read_csv(f"{data}/stress.csv")


def heat(ax, xkey, ykey, xfmt, yfmt, xlabel, ylabel):
    xs = sorted({num(r[xkey]) for r in rows})
    ys = sorted({num(r[ykey]) for r in rows})
    frac = np.full((len(ys), len(xs)), np.nan)
    label = [["" for _ in xs] for _ in ys]
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            cell = [r for r in rows if num(r[xkey]) == x and num(r[ykey]) == y]
            if cell:
                p = sum(int(r["pass"]) for r in cell)
                frac[i, j] = p / len(cell)
                label[i][j] = f"{p}/{len(cell)}"
    im = ax.imshow(frac, vmin=0, vmax=1, cmap="RdYlGn", origin="lower", aspect="auto")
    for i in range(len(ys)):
        for j in range(len(xs)):
            ax.text(j, i, label[i][j], ha="center", va="center", fontsize=8)
    ax.set_xticks(range(len(xs)), [xfmt(x) for x in xs], fontsize=7)
    ax.set_yticks(range(len(ys)), [yfmt(y) for y in ys], fontsize=7)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return im


fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6))
heat(a, "dt", "youngs_modulus", lambda x: f"{x*1e3:.3g}", lambda y: f"{y*1e-9:g}", "dt [ms]", "E [GPa]")
im = heat(b, "flow_scale", "friction", lambda x: f"x{x:g}", lambda y: f"{y:g}", "flow amplitude (drag scale)", "friction")
fig.colorbar(im, ax=b, label="fraction passing")
npass = sum(int(r["pass"]) for r in rows)
fig.suptitle(f"stress matrix, aortic arch: {npass}/{len(rows)} runs pass", fontsize=9)
save(fig, f"{out}/stress_heatmap.png")
