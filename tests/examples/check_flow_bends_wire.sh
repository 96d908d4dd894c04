#!/usr/bin/env bash
# Blood bends the soft angled tip: with the drag law the tip swings by more than a
# millimetre over the first beats; without it, it stays put sideways (within 0.01 mm).
set -euo pipefail
flowire=$1 out=$2
here="$(cd "$(dirname "$0")" && pwd)"
rm -rf "$out"
FLOWIRE="$flowire" bash "$here/../../examples/flow_bends_wire/run.sh" "$out" --quick
/usr/bin/python3 - "$out" <<'PY'
import csv, sys
out = sys.argv[1]
def lateral(run):
    rows = list(csv.DictReader(open(f"{out}/{run}/tip_trace.csv")))
    ys = [float(r["y"]) for r in rows]
    return max(ys) - min(ys)
on, off = lateral("drag_cylinder"), lateral("drag_none")
print(f"sideways swing of the tip: flow on {on*1e3:.3f} mm, flow off {off*1e3:.6f} mm")
assert off < 1e-5, "without drag the tip must stay put sideways (within 0.01 mm)"
assert on > 1e-3, "the blood must swing the soft tip by more than 1 mm"
PY
