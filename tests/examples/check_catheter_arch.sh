#!/usr/bin/env bash
# The catheter example up to t = 2 s, past where the wire's pre-shaped tip leaves the catheter
# (t ≈ 1.1–1.3 s, where the catheter's Newton failed before its tip was tapered): both rods
# converge in every step, the wire is out of the catheter's tip and stays in its lumen inside.
set -euo pipefail
flowire=$1 scene=$2 out=$3
rm -rf "$out"
"$flowire" run "$scene" --out "$out" --set output.vtk=false --set output.csv=false --set solve.duration=2s
/usr/bin/python3 - "$out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
w, c = s["wire"], s["catheter"]
print(f"unconverged steps: wire {w['unconverged_steps']}, catheter {c['unconverged_steps']}; "
      f"inserted: wire {w['inserted_length']:.4f} m, catheter {c['inserted_length']:.4f} m; "
      f"offset / clearance {c['max_wire_offset_over_clearance']:.3f}")
assert w["unconverged_steps"] == 0 and c["unconverged_steps"] == 0, "every step of both rods must converge"
assert w["inserted_length"] > c["inserted_length"] + 0.005, "the wire must be out of the catheter's tip"
tip_gap = sum((a - b) ** 2 for a, b in zip(w["tip"], c["tip"])) ** 0.5
assert tip_gap > 0.005, f"the wire's tip must be away from the catheter's ({tip_gap:.4f} m)"
assert c["max_wire_offset_over_clearance"] < 1.2, "the wire must stay in the lumen"
# The tube's bending stiffness E·π(ro⁴ − ri⁴)/4 of the scene's 2 GPa, 1 mm / 0.55 mm section.
import math
ei = 2e9 * math.pi * (1e-3 ** 4 - 0.55e-3 ** 4) / 4
assert abs(c["bending_stiffness"] - ei) <= 1e-9 * ei, f"catheter EI {c['bending_stiffness']} != {ei}"
PY
