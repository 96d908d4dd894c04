#!/usr/bin/env bash
# A catheter parked in the aortic arch and a guidewire advanced out of it towards the left
# subclavian artery (docs/catheter.md). Writes wire/catheter CSV and VTK series; prints the
# two tips, the wire's largest offset from the catheter's axis over the lumen clearance and
# the unconverged steps of both rods.
# usage: examples/catheter_arch/run.sh [OUT_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
OUT=${1:-out/catheter_arch}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
"$FLOWIRE" run "$here/scene.yaml" --out "$OUT"
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
w, c = s["wire"], s["catheter"]
print(f"wire tip      {w['tip']} m, inserted {w['inserted_length']:.4f} m, unconverged steps {w['unconverged_steps']}")
print(f"catheter tip  {c['tip']} m, inserted {c['inserted_length']:.4f} m, unconverged steps {c['unconverged_steps']}")
print(f"wire offset from the catheter axis / clearance: {c['max_wire_offset_over_clearance']:.3f}")
print(f"steering steps (tip near the left subclavian): {s.get('tip_forces', {}).get('steering_steps')}")
PY
