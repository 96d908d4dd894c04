"""examples/python/sweep.py runs (a 3 cm push at two speeds) and writes what it says: every
run pushed the asked length (speed x steps x dt, to one step), the distances are finite,
and the picture exists."""
import csv
import pathlib
import subprocess
import sys

root = pathlib.Path(__file__).resolve().parents[2]
out = pathlib.Path(sys.argv[1])
subprocess.run([sys.executable, str(root / "examples/python/sweep.py"), "--length", "0.03", "--speeds", "1,2",
                "--out", str(out)], check=True)
rows = list(csv.DictReader(open(out / "sweep.csv")))
assert [float(r["speed"]) for r in rows] == [0.01, 0.02], rows
dt = 0.01  # solve.dt of examples/aortic_arch/scene.yaml
for r in rows:
    assert abs(float(r["pushed"]) - 0.03) <= float(r["speed"]) * dt / 2 + 1e-12, r
    assert 0 <= float(r["rms_distance"]) <= float(r["max_distance"]) < 0.01, r
assert (out / "sweep.png").stat().st_size > 20000
print("ok:", rows)
