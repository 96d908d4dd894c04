#!/usr/bin/env python3
"""Pictures of a run with a deformable wall around a vessel that winds in the plane z = 0: the
wall's displacement seen from above at the frame where it is largest, and the wall's section
by the plane z = 0 at rest and deformed (to scale), with the wire (and a catheter, if any). Usage: plot_tortuous.py OUT_DIR  (writes OUT_DIR/wall.png)."""
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
    largest, x, u = largest_frame(out, "plot_tortuous.py")
    mag = np.linalg.norm(u, axis=1)
    # The wall's section by the plane z = 0 (its nodes within a quarter millimetre of it).
    thickness_band = np.abs(x[:, 2]) < 0.25e-3
    fig, (a, b) = plt.subplots(2, 1, figsize=(10, 8))
    order = np.argsort(mag)
    sc = a.scatter(x[order, 0] * 1e3, x[order, 1] * 1e3, c=mag[order] * 1e3, s=4, cmap="viridis")
    fig.colorbar(sc, ax=a, label="|displacement| [mm]")
    a.set_aspect("equal")
    a.set_xlabel("x [mm]")
    a.set_ylabel("y [mm]")
    a.set_title(f"wall seen from above, frame {largest}: largest displacement {mag.max() * 1e3:.3f} mm")
    s = thickness_band
    b.scatter(x[s, 0] * 1e3, x[s, 1] * 1e3, s=2, c="0.6", label="wall at rest (section z = 0)")
    b.scatter((x[s, 0] + u[s, 0]) * 1e3, (x[s, 1] + u[s, 1]) * 1e3, s=2, c="C3", label=f"deformed, frame {largest}")
    for name, style in (("wire", dict(color="C0", lw=2)), ("catheter", dict(color="C2", lw=5, alpha=0.6))):
        rod = rod_at_frame(out, name, largest)
        if not rod:
            continue
        w, t = rod
        b.plot(w["x"] * 1e3, w["y"] * 1e3, label=f"{name}, t = {t:.2f} s", **style)
    b.set_aspect("equal")
    b.set_xlabel("x [mm]")
    b.set_ylabel("y [mm]")
    b.legend(loc="upper right", fontsize=8, markerscale=4)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "wall.png"), dpi=120)
    print(os.path.join(out, "wall.png"))


if __name__ == "__main__":
    main()
