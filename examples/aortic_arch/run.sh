#!/usr/bin/env bash
# The published experiment: a J-tipped 0.035" wire pushed 50 cm from the right femoral
# artery towards the aortic root at 1, 1.5 and 2 cm/s, with and without the blood flow.
# Writes, per run, VTK series (network.pvd, wire.pvd) and tip_trace.csv; then the RMS
# table between flow on and off per speed (like the published Table 2) and PNGs.
# usage: examples/aortic_arch/run.sh [OUT_DIR] [--quick]   (--quick: 5 cm, for CI)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
OUT=${1:-out/aortic_arch}
QUICK=${2:-}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
PY=${PYTHON:-/usr/bin/python3}   # Debian python3 with python3-matplotlib
# A virtual X server for the PNGs, unless there is a display already (e.g. ctest under xvfb-run).
XR=()
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then XR=(xvfb-run -a -s "-screen 0 1024x768x24"); fi
mkdir -p "$OUT"
for speed in 1 1.5 2; do
  length_s=$(python3 -c "print(0.48 / ($speed / 100))")   # push 48 cm (50 cm with the 2 cm start)
  extra=()
  if [ "$QUICK" = "--quick" ]; then
    length_s=$(python3 -c "print(0.05 / ($speed / 100))")
    extra=(--set output.every=1s --set output.png=false)   # CI: no X server needed
  fi
  for mode in on off; do
    drag=cylinder
    [ "$mode" = off ] && drag=none
    "${XR[@]}" "$FLOWIRE" run "$here/scene.yaml" --out "$OUT/v${speed}_$mode" \
      --set "insertion.speed=${speed} cm/s" --set "solve.duration=${length_s} s" \
      --set "coupling.drag=$drag" --set output.png=true ${extra[@]+"${extra[@]}"}
  done
  "$FLOWIRE" compare "$OUT/v${speed}_on/tip_trace.csv" "$OUT/v${speed}_off/tip_trace.csv" \
    --out "$OUT/compare_v${speed}.csv" | tee "$OUT/compare_v${speed}.txt"
  "$PY" "$root/tools/plot/plot_traces.py" "$OUT/traces_v${speed}.png" \
    "flow on=$OUT/v${speed}_on/tip_trace.csv" "flow off=$OUT/v${speed}_off/tip_trace.csv" \
    --compare "$OUT/compare_v${speed}.csv"
done
echo "outputs in $OUT: open */network.pvd and */wire.pvd in ParaView; pictures: $OUT/*.png, $OUT/*/network*.png"
