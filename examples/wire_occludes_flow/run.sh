#!/usr/bin/env bash
# The wire in one daughter of a coronary Y, with and without its occlusion of the flow, and
# with the outlets at a common pressure (conduit) and through a microvascular resistance
# (physiological). Writes OUT/split.md (the flow split of each case) and OUT/*/network.png.
# Usage: examples/wire_occludes_flow/run.sh [OUT]   (FLOWIRE=path/to/flowire to choose the binary)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-out/wire_occludes_flow}
flowire=${FLOWIRE:-$here/../../build/tools/flowire}
mkdir -p "$out"
XR=()  # the pictures need an X server: a virtual one when there is no display
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then XR=(xvfb-run -a -s "-screen 0 1024x768x24"); fi
run() {  # name, extra --set arguments
  local name=$1; shift
  "$flowire" run "$here/scene.yaml" --out "$out/$name" "$@" >/dev/null
}
# The pressure field with the wire in it, and without it for comparison.
"${XR[@]}" "$flowire" run "$here/scene.yaml" --out "$out/conduit_annulus" --set output.png=true >/dev/null
"${XR[@]}" "$flowire" run "$here/scene.yaml" --out "$out/conduit_none" --set output.png=true \
  --set coupling.occlusion=none >/dev/null
# Coronary microvascular resistance at rest: ~90 mmHg over ~0.5 mL/s per daughter.
micro=(--set flow.inlet.pressure=100mmHg --set flow.outlets.resistance=180mmHg*s/mL)
run micro_annulus "${micro[@]}"
run micro_none "${micro[@]}" --set coupling.occlusion=none
/usr/bin/python3 "$here/split.py" "$out" conduit_none conduit_annulus micro_none micro_annulus > "$out/split.md"
cat "$out/split.md"
