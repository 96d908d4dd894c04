#!/usr/bin/env bash
# Wires in real lumens: every scene of this folder (one per anatomy of ../shared/data/real with
# a lumen surface and a centerline), each writing its outputs and network.png (pressure at peak
# inlet with the wire over it) to OUT_DIR/<scene>. Skipped, saying so, without the shared data.
# usage: examples/real/run.sh [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
OUT=${1:-out/real}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
shared="$(cd "$root/.." && pwd)/shared/data/real"
if [ ! -d "$shared" ]; then
  echo "examples/real: skipped: the shared reference data is not at $shared (the scenes read it from ../shared)"
  exit 0
fi
if command -v xvfb-run >/dev/null; then RUN=(xvfb-run -a -s "-screen 0 1024x768x24"); else RUN=(); fi
mkdir -p "$OUT"
for scene in feelpp_arch feelpp_arch_wall vmtk_abdominal simvascular_aorta aneurisk_ica aortofemoral_deck; do
  "${RUN[@]}" "$FLOWIRE" run "$here/$scene.yaml" --out "$OUT/$scene" --set output.png=true
done
"${PYTHON:-/usr/bin/python3}" "$here/plot_real_wall.py" "$OUT/feelpp_arch_wall"
echo "pictures: $OUT/*/network.png, $OUT/feelpp_arch_wall/wall.png; open $OUT/*/wire.pvd (and $OUT/feelpp_arch_wall/wall.pvd) with the surfaces of $shared in ParaView"
