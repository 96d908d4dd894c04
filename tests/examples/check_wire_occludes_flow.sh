#!/usr/bin/env bash
# A 0.014" wire in one daughter of a coronary Y: with the outlets at a common pressure the
# daughter's share of the flow falls well below half (the annulus' resistance); through a
# microvascular resistance the split hardly moves; ignoring the wire, the split is even.
set -euo pipefail
flowire=$1 out=$2
rm -rf "$out"
FLOWIRE=$flowire bash "$(dirname "$0")/../../examples/wire_occludes_flow/run.sh" "$out" >/dev/null
test -s "$out/conduit_annulus/network.png"
/usr/bin/python3 - "$out/split.md" <<'PY'
import sys
rows = {}
for line in open(sys.argv[1]):
    c = [x.strip() for x in line.strip().strip("|").split("|")]
    if len(c) == 6 and c[0] and not c[0].startswith("run") and not c[0].startswith("-"):
        rows[c[0]] = float(c[4].rstrip("%")) / 100
print(rows)
assert abs(rows["conduit_none"] - 0.5) < 0.005, "without occlusion the symmetric Y splits evenly"
assert rows["conduit_annulus"] < 0.47, "the wire's daughter must lose flow in the conduit case"
assert abs(rows["micro_annulus"] - 0.5) < 0.01, "the microvascular resistance dominates the split"
PY
