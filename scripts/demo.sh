#!/usr/bin/env bash
# Install dependencies, build flowire and run the demo scene on built-in geometry.
# Usage: scripts/demo.sh [scene.yaml] [extra flowire run arguments...]
# With a wire in the scene it also runs it without blood drag and plots both tip traces.
set -euo pipefail
cd "$(dirname "$0")/.."
SCENE=${1:-examples/aortic_arch/scene.yaml}
shift || true
bash scripts/install-deps.sh
cmake --preset default -B build >/dev/null
cmake --build build -j"$(nproc)" --target flowire
if command -v xvfb-run >/dev/null; then RUN=(xvfb-run -a -s "-screen 0 1024x768x24"); else RUN=(); fi
"${RUN[@]}" ./build/tools/flowire run "$SCENE" --out out/demo --set output.png=true "$@"
if [ -f out/demo/tip_trace.csv ]; then
  # The same push without the blood acting on the wire, and the two tip traces side by side.
  ./build/tools/flowire run "$SCENE" --out out/demo/flow_off --set coupling.drag=none --set output.vtk=false "$@"
  ./build/tools/flowire compare out/demo/tip_trace.csv out/demo/flow_off/tip_trace.csv --out out/demo/compare.csv
  /usr/bin/python3 tools/plot/plot_traces.py out/demo/tip_traces.png "flow on=out/demo/tip_trace.csv" \
    "flow off=out/demo/flow_off/tip_trace.csv" --compare out/demo/compare.csv
fi
echo "demo outputs in out/demo: network.png (pressure at peak inlet, wire over it), tip_traces.png (flow on/off);"
echo "open network.pvd and wire.pvd in ParaView"
