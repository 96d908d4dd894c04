#!/usr/bin/env python3
"""Pictures of a run with a deformable wall: the wall's displacement on the unrolled lumen at
the frame where it is largest, and the wall's section through the tip's plane at rest and
deformed, with the wire. Usage: plot_wall.py OUT_DIR  (writes OUT_DIR/wall.png)."""
import glob
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def read_vtu(path):
    text = open(path).read()

    def array(name, columns):
        start = text.index(f'Name="{name}"')
        body = text[text.index(">", start) + 1:text.index("</DataArray>", start)]
        return np.array(body.split(), dtype=float).reshape(-1, columns)

    points_at = text.index("<Points>")
    body = text[text.index(">", text.index("<DataArray", points_at)) + 1:text.index("</DataArray>", points_at)]
    return np.array(body.split(), dtype=float).reshape(-1, 3), array("displacement", 3)


def largest_frame(out, script):
    """The wall frame of OUT where the displacement is largest: (its index, points, displacement)."""
    frames = sorted(glob.glob(os.path.join(out, "wall_*.vtu")))
    if not frames:
        sys.exit(f"{script}: no wall_*.vtu in {out}")
    states = [read_vtu(f) for f in frames]
    largest = max(range(len(states)), key=lambda k: np.linalg.norm(states[k][1], axis=1).max())
    return (largest, *states[largest])


def rod_at_frame(out, name, frame):
    """The rod NAME (wire, catheter) of OUT at output frame FRAME, from NAME.csv: (its rows, the
    time), or None without the file."""
    path = os.path.join(out, f"{name}.csv")
    if not os.path.exists(path):
        return None
    data = np.genfromtxt(path, delimiter=",", names=True)
    times = np.unique(data["time"])
    t = times[min(frame, len(times) - 1)]
    return data[data["time"] == t], t


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    largest, x, u = largest_frame(out, "plot_wall.py")
    radius = np.hypot(x[:, 1], x[:, 2])
    lumen = radius < radius.min() + 1e-6 + 0.02 * (radius.max() - radius.min())
    theta = np.degrees(np.arctan2(x[:, 2], x[:, 1]))
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 7.5))
    sc = a.scatter(x[lumen, 0] * 1e3, theta[lumen], c=np.linalg.norm(u[lumen], axis=1) * 1e3, s=6, cmap="viridis")
    fig.colorbar(sc, ax=a, label="|displacement| [mm]")
    a.set_xlabel("x along the vessel [mm]")
    a.set_ylabel("angle around it [deg] (0: +y)")
    a.set_title(f"lumen displacement, frame {largest} (largest: {np.linalg.norm(u, axis=1).max() * 1e3:.3f} mm)")
    # The section through the plane z = 0, the side y > 0 where the J presses.
    side = lumen & (np.abs(x[:, 2]) < 0.15 * radius.min()) & (x[:, 1] > 0)
    order = np.argsort(x[side, 0])
    xs, ys = x[side][order], u[side][order]
    b.plot(xs[:, 0] * 1e3, xs[:, 1] * 1e3, "k--", label="lumen at rest")
    b.plot((xs[:, 0] + ys[:, 0]) * 1e3, (xs[:, 1] + ys[:, 1]) * 1e3, "C3", label=f"lumen, frame {largest}")
    rod = rod_at_frame(out, "wire", largest)
    if rod:
        w, t = rod
        b.plot(w["x"] * 1e3, w["y"] * 1e3, "C0", lw=2, label=f"wire, t = {t:.2f} s")
    b.set_xlabel("x [mm]")
    b.set_ylabel("y [mm]")
    b.set_title("section z = 0")
    b.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "wall.png"), dpi=120)
    print(os.path.join(out, "wall.png"))


if __name__ == "__main__":
    main()
