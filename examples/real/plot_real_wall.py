#!/usr/bin/env python3
"""Pictures of a run with a deformable wall around a real lumen surface: the wall seen along the
axis its nodes spread least in (the anatomy's own plane), coloured by |displacement| at the frame
where it is largest, with the wire at that frame; and beside it the same at rest and deformed
(displacement magnified) where the wire presses most. Usage: plot_real_wall.py OUT_DIR
(writes OUT_DIR/wall.png)."""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "deformable_wall"))
from plot_wall import largest_frame, rod_at_frame  # noqa: E402  (the wall frame where it moved most)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    largest, x, u = largest_frame(out, "plot_real_wall.py")
    mag = np.linalg.norm(u, axis=1)
    centre = x.mean(axis=0)
    # The anatomy's plane: the two directions its nodes spread most in.
    _, _, axes = np.linalg.svd(x - centre, full_matrices=False)
    e1, e2, e3 = axes
    p = (x - centre) @ np.array([e1, e2]).T
    wire = None
    rod = rod_at_frame(out, "wire", largest)
    if rod:
        w, t = rod
        wire = (np.column_stack([w["x"], w["y"], w["z"]]) - centre) @ np.array([e1, e2]).T, t
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 6))
    order = np.argsort(mag)
    sc = a.scatter(p[order, 0] * 1e3, p[order, 1] * 1e3, c=mag[order] * 1e3, s=3, cmap="viridis")
    fig.colorbar(sc, ax=a, label="|displacement| [mm]")
    if wire is not None:
        a.plot(wire[0][:, 0] * 1e3, wire[0][:, 1] * 1e3, color="C3", lw=1.5, label=f"wire, t = {wire[1]:.2f} s")
        a.legend(loc="best", fontsize=8)
    a.set_aspect("equal")
    a.set_title(f"wall, frame {largest}: largest displacement {mag.max() * 1e3:.3f} mm")
    a.set_xlabel("[mm]")
    # Around the node that moved most: the wall at rest and deformed (x10), in a slab of the plane.
    k = int(np.argmax(mag))
    depth = (x - x[k]) @ e3
    slab = (np.abs(depth) < 1.0e-3) & (np.linalg.norm(x - x[k], axis=1) < 25e-3)
    scale = 10.0
    q = (x[slab] - centre) @ np.array([e1, e2]).T
    qd = (x[slab] + scale * u[slab] - centre) @ np.array([e1, e2]).T
    b.scatter(q[:, 0] * 1e3, q[:, 1] * 1e3, s=3, c="0.6", label="wall at rest (slab through the largest motion)")
    b.scatter(qd[:, 0] * 1e3, qd[:, 1] * 1e3, s=3, c="C3", label=f"deformed, displacement x{scale:g}")
    if wire is not None:
        near = np.linalg.norm(wire[0] - p[k], axis=1) < 25e-3
        b.plot(wire[0][near, 0] * 1e3, wire[0][near, 1] * 1e3, color="C0", lw=2, label="wire")
    b.set_aspect("equal")
    b.set_xlabel("[mm]")
    b.legend(loc="best", fontsize=8, markerscale=4)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "wall.png"), dpi=110)
    print(os.path.join(out, "wall.png"))


if __name__ == "__main__":
    main()
