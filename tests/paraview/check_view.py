"""Run by pvpython: load a flowire run's view.py and check what ParaView shows against the
run's own CSV files (node count, pressure range, wire vertices), then render a picture.
Usage: pvpython check_view.py OUTPUT_DIR PICTURE.png"""
import csv
import importlib.util
import os
import sys

from paraview import servermanager
from paraview.simple import GetAnimationScene, GetColorTransferFunction, SaveScreenshot

out, picture = sys.argv[1], sys.argv[2]
spec = importlib.util.spec_from_file_location("view", os.path.join(out, "view.py"))
view = importlib.util.module_from_spec(spec)
spec.loader.exec_module(view)          # defines load(); does not render (not __main__)
shown = view.load(out)

scene = GetAnimationScene()
times = list(scene.TimeKeeper.TimestepValues or [])
last = times[-1] if times else 0.0
scene.AnimationTime = last


def rows(name):
    with open(os.path.join(out, name)) as f:
        return list(csv.DictReader(f))


failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


# the network at the last output time: its nodes and pressures as nodes.csv has them
nodes = [r for r in rows("nodes.csv") if abs(float(r["time"]) - float(rows("nodes.csv")[-1]["time"])) < 1e-12]
net = shown["network"]
net.UpdatePipeline(last)
data = servermanager.Fetch(net)
block = data.GetBlock(0) if data.IsA("vtkMultiBlockDataSet") else data
check(block.GetNumberOfPoints() == len(nodes), f"network points {block.GetNumberOfPoints()} == nodes.csv rows {len(nodes)}")
lo, hi = net.PointData["pressure"].GetRange()
p = [float(r["pressure"]) for r in nodes]
check(abs(lo - min(p)) <= 1e-6 * max(abs(min(p)), 1.0) and abs(hi - max(p)) <= 1e-6 * max(abs(max(p)), 1.0),
      f"pressure range [{lo:.6g}, {hi:.6g}] == nodes.csv [{min(p):.6g}, {max(p):.6g}] at t = {last:g}")
check(shown["field"] == "pressure", "the network is coloured by pressure")
color = shown["network_display"].ColorArrayName
check(list(color) == ["POINTS", "pressure"], f"network display colour array {list(color)}")
check(shown["network_tubes"].VaryRadius == "By Absolute Scalar", "network tubes at the vessels' radii")
# the tubes reach one vessel radius beyond the centerline's bounds, no more
b_line = net.GetDataInformation().GetBounds()
b_tube = shown["network_tubes"].GetDataInformation().GetBounds()
r_max = max(float(r["radius"]) for r in rows("segments.csv"))
grow = max(max(b_line[2 * k] - b_tube[2 * k], b_tube[2 * k + 1] - b_line[2 * k + 1]) for k in range(3))
check(0 < grow <= 1.01 * r_max, f"tube bounds grow by {grow:.4g} m, at most the largest radius {r_max:.4g} m")

# the wire at the last output time: as many points as wire.csv has vertices then
wire_rows = rows("wire.csv")
t_last = float(wire_rows[-1]["time"])
n_wire = sum(1 for r in wire_rows if abs(float(r["time"]) - t_last) < 1e-12)
wire = shown["wire"]
wire.UpdatePipeline(last)
wdata = servermanager.Fetch(wire)
check(wdata.GetNumberOfPoints() == n_wire, f"wire points {wdata.GetNumberOfPoints()} == wire.csv vertices {n_wire}")
check(abs(shown["wire_tube"].Radius - view.WIRE_DRAW_RADIUS) < 1e-15, "wire drawn at WIRE_DRAW_RADIUS")

check(list(GetColorTransferFunction("pressure").RGBPoints)[0::4][0] == lo, "colours span this output's pressures")
if os.environ.get("DISPLAY"):
    SaveScreenshot(picture, shown["view"], ImageResolution=[800, 600])
    check(os.path.getsize(picture) > 10000, f"{picture} rendered ({os.path.getsize(picture)} bytes)")
else:
    print("no DISPLAY: the picture is not rendered (run under xvfb-run)")

sys.stdout.flush()
os._exit(1 if failures else 0)  # skip ParaView's teardown of the render window (it can crash at exit)
