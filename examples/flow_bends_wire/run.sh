#!/usr/bin/env bash
# Blood bends a soft-tipped wire: the scene with the flow acting on the wire and without,
# the distance between the two tip traces by inserted length, and a picture of both.
# usage: examples/flow_bends_wire/run.sh [OUT_DIR] [--quick]   (--quick: 3 s, no PNG, for CI)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
OUT=${1:-out/flow_bends_wire}
QUICK=${2:-}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
PY=${PYTHON:-/usr/bin/python3}   # Debian python3 with python3-matplotlib
extra=()
if [ "$QUICK" = "--quick" ]; then extra=(--set solve.duration=3s --set output.every=0.5s); fi
mkdir -p "$OUT"
for drag in cylinder none; do
  "$FLOWIRE" run "$here/scene.yaml" --out "$OUT/drag_$drag" --set "coupling.drag=$drag" ${extra[@]+"${extra[@]}"}
done
"$FLOWIRE" compare "$OUT/drag_cylinder/tip_trace.csv" "$OUT/drag_none/tip_trace.csv" --out "$OUT/compare.csv" \
  | tee "$OUT/compare.txt"
if [ "$QUICK" != "--quick" ]; then
  "$PY" "$root/tools/plot/plot_traces.py" "$OUT/traces.png" \
    "flow on=$OUT/drag_cylinder/tip_trace.csv" "flow off=$OUT/drag_none/tip_trace.csv" --views x:y,time:y
  echo "picture: $OUT/traces.png; open $OUT/drag_*/wire.pvd and network.pvd in ParaView"
fi
