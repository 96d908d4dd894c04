#!/usr/bin/env bash
# Behaviour check for refactors: run every example scene (short runs, no pictures or VTK) and
# compare its summary.json (timings and paths left out) and CSV outputs with a baseline run.
#   scripts/compare-examples.sh record DIR   # run them all into DIR
#   scripts/compare-examples.sh check DIR    # run them again into DIR.new and diff with DIR
# Scenes that need ../shared are skipped, saying so, where it is absent. The FEM examples are
# left out (minutes each; their own tests compare them with references), and so are the studies
# (flowire study runs scenes like these).
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=${1:?record or check}
BASE=${2:?output directory}
OUT=$BASE
[ "$MODE" = check ] && OUT=$BASE.new
FLOWIRE=${FLOWIRE:-build/tools/flowire}
rm -rf "$OUT" && mkdir -p "$OUT"
SETS=(--set output.vtk=false --set output.png=false)
status=0
for scene in $(find examples -name '*.yaml' -not -path '*/fem_*' -not -path '*/studies/*' | sort); do
  name=$(echo "${scene#examples/}" | tr '/' '_' | sed 's/\.yaml$//')
  if grep -q '\.\./shared' "$scene" && [ ! -d ../shared ]; then
    echo "skip $scene: ../shared is absent"
    continue
  fi
  extra=()
  grep -q '^solve:' "$scene" && extra=(--set solve.duration=1s)
  if ! "$FLOWIRE" run "$scene" --out "$OUT/$name" "${SETS[@]}" "${extra[@]}" >"$OUT/$name.log" 2>&1; then
    echo "run failed: $scene (see $OUT/$name.log)"
    status=1
  fi
done
[ "$MODE" = record ] && exit $status
/usr/bin/python3 - "$BASE" "$OUT" <<'PY' || status=1
import json, pathlib, sys, filecmp
base, new = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
def clean(x):
    if isinstance(x, dict):
        # run times and the output folder are not behaviour
        return {k: clean(v) for k, v in x.items() if k not in ("timings", "dir", "output.dir") and "seconds" not in k and not k.endswith("_ms")}
    if isinstance(x, list):
        return [clean(v) for v in x]
    return x
bad = 0
for d in sorted(p for p in base.iterdir() if p.is_dir()):
    n = new / d.name
    for f in sorted(d.rglob("*")):
        if f.suffix not in (".json", ".csv") or not f.is_file():
            continue
        g = n / f.relative_to(d)
        if not g.exists():
            print(f"missing: {g}"); bad += 1; continue
        if f.suffix == ".json":
            same = clean(json.loads(f.read_text())) == clean(json.loads(g.read_text()))
        else:
            same = filecmp.cmp(f, g, shallow=False)
        if not same:
            print(f"differs: {f.relative_to(base)}"); bad += 1
print("identical" if bad == 0 else f"{bad} files differ")
sys.exit(1 if bad else 0)
PY
exit $status
