#!/usr/bin/env bash
# A catheter parked in the aortic arch and a guidewire advanced out of it towards the left
# subclavian artery (docs/catheter.md). Writes wire/catheter CSV and VTK series and
# network.png / network_side.png (the network with the catheter, orange, and the wire out of
# its tip, dark; needs an X server: run under xvfb-run when there is none); prints the two
# tips, the wire's largest offset from the catheter's axis over the lumen clearance and the
# unconverged steps of both rods.
# usage: examples/catheter_arch/run.sh [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
OUT=${1:-out/catheter_arch}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then RUN=(xvfb-run -a -s "-screen 0 1024x768x24"); else RUN=(); fi
"${RUN[@]}" "$FLOWIRE" run "$here/scene.yaml" --out "$OUT" --set output.png=true
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
w, c = s["wire"], s["catheter"]
print(f"wire tip      {w['tip']} m, inserted {w['inserted_length']:.4f} m, unconverged steps {w['unconverged_steps']}")
print(f"catheter tip  {c['tip']} m, inserted {c['inserted_length']:.4f} m, unconverged steps {c['unconverged_steps']}")
print(f"wire offset from the catheter axis / clearance: {c['max_wire_offset_over_clearance']:.3f}")
print(f"steering steps (tip near the left subclavian): {s.get('tip_forces', {}).get('steering_steps')}")
PY
echo "pictures: $OUT/network.png, $OUT/network_side.png; open $OUT/wire.pvd and $OUT/catheter.pvd in ParaView"
