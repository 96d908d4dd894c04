#!/usr/bin/env bash
# Install dependencies, build flowire and run the demo scene on built-in geometry.
# Usage: scripts/demo.sh [scene.yaml] [extra flowire run arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
SCENE=${1:-examples/aortic_arch/scene.yaml}
shift || true
bash scripts/install-deps.sh
cmake --preset default -B build >/dev/null
cmake --build build -j"$(nproc)" --target flowire
if command -v xvfb-run >/dev/null; then RUN=(xvfb-run -a -s "-screen 0 1024x768x24"); else RUN=(); fi
"${RUN[@]}" ./build/tools/flowire run "$SCENE" --out out/demo --set output.png=true "$@"
echo "demo outputs in out/demo (open network.pvd / wire.pvd in ParaView)"
