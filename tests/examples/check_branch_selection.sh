#!/usr/bin/env bash
# Turning the J tip by 180 degrees at the base sends the wire into the other daughter.
set -euo pipefail
flowire=$1 scene=$2 out=$3
rm -rf "$out"
"$flowire" run "$scene" --out "$out/a0" --set output.vtk=false
"$flowire" run "$scene" --out "$out/a180" --set output.vtk=false --set insertion.rotation_angle=180deg
/usr/bin/python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
y0 = json.load(open(f"{out}/a0/summary.json"))["wire"]["tip"][1]
y1 = json.load(open(f"{out}/a180/summary.json"))["wire"]["tip"][1]
print(f"tip y at 0 deg: {y0*1e3:.2f} mm, at 180 deg: {y1*1e3:.2f} mm")
assert abs(y0) > 0.008 and abs(y1) > 0.008 and y0 * y1 < 0, "the two rotations must end in different daughters"
PY
