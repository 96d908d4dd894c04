#!/usr/bin/env python3
"""Flow on and off over insertion speeds, from Python: the aortic-arch push of
examples/aortic_arch stepped with flowire.CoSimulation, the insertion set at every step,
the tip and the clamp force read after it. Plots the tip paths, the distance between the
flow-on and flow-off tips by inserted length, and the clamp force (sweep.png), and writes
the numbers (sweep.csv).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/sweep.py --out out/sweep
    /usr/bin/python3 examples/python/sweep.py --length 0.05      # a 5 cm push (installed flowire)
The default, 48 cm at 1, 1.5 and 2 cm/s (six runs), took 88 s on a 2-core machine.
"""
import argparse
import csv
import os
import pathlib
import time

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import flowire  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
SCENE = HERE.parent / "aortic_arch" / "scene.yaml"


def push(speed, drag, length):
    """Push the wire `length` metres at `speed` m/s; the tip and clamp force after every step."""
    sim = flowire.CoSimulation(SCENE, set={"coupling.drag": drag})
    start = sim.inserted_length
    steps = int(round(length / speed / sim.dt))
    rows = []
    for _ in range(steps):
        sim.insertion_speed = speed          # a controller could change it here, step by step
        sim.step()
        x = sim.wire()["x"]                  # base → tip
        direction = x[1] - x[0]              # the insertion direction at the clamp
        direction /= np.linalg.norm(direction)
        rows.append((sim.time, sim.inserted_length, *sim.tip, float(sim.base_force @ direction)))
    return start, np.array(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speeds", default="1,1.5,2", help="insertion speeds in cm/s (default 1,1.5,2)")
    ap.add_argument("--length", type=float, default=0.48, help="pushed length in m (default 0.48, the published push)")
    ap.add_argument("--out", default="out/python_sweep", help="output folder")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    speeds = [float(s) / 100 for s in a.speeds.split(",")]

    fig, (ax_path, ax_dist, ax_force) = plt.subplots(1, 3, figsize=(16, 5))
    table = []
    for speed in speeds:
        t0 = time.perf_counter()
        runs = {mode: push(speed, drag, a.length) for mode, drag in (("on", "cylinder"), ("off", "none"))}
        (start, on), (_, off) = runs["on"], runs["off"]
        distance = np.linalg.norm(on[:, 2:5] - off[:, 2:5], axis=1)   # same steps: same inserted length
        rms = float(np.sqrt(np.mean(distance**2)))
        table.append((speed, a.length, on[-1, 1] - start, rms, distance.max(), time.perf_counter() - t0))
        label = f"{speed * 100:g} cm/s"
        line, = ax_path.plot(on[:, 2] * 1e3, on[:, 4] * 1e3, label=f"{label} flow on")
        ax_path.plot(off[:, 2] * 1e3, off[:, 4] * 1e3, "--", color=line.get_color(), label=f"{label} flow off")
        ax_dist.plot((on[:, 1] - start) * 1e3, distance * 1e3, color=line.get_color(), label=label)
        ax_force.plot((on[:, 1] - start) * 1e3, on[:, 5], color=line.get_color(), label=f"{label} flow on")
        ax_force.plot((off[:, 1] - start) * 1e3, off[:, 5], "--", color=line.get_color(), label=f"{label} flow off")
        print(f"{label}: RMS distance flow on/off {rms * 1e3:.4f} mm, max {distance.max() * 1e3:.4f} mm "
              f"({table[-1][-1]:.1f} s)")
    ax_path.set(title="tip path (side view)", xlabel="x [mm]", ylabel="z [mm]")
    ax_dist.set(title="tip distance, flow on vs off", xlabel="pushed length [mm]", ylabel="distance [mm]")
    ax_force.set(title="clamp force on the wire, along the insertion", xlabel="pushed length [mm]", ylabel="force [N]")
    for ax in (ax_path, ax_dist, ax_force):
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "sweep.png", dpi=110)
    with open(out / "sweep.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["speed", "length", "pushed", "rms_distance", "max_distance", "seconds"])
        w.writerows(table)
    print(f"wrote {out / 'sweep.png'} and {out / 'sweep.csv'}")


if __name__ == "__main__":
    main()
