#!/usr/bin/env bash
# The view.py of a flowire run opens in ParaView: run a short scene with VTK output, then load
# its view.py in pvpython and check what it shows against the run's CSV files.
# Usage: check_view.sh FLOWIRE PVPYTHON WORKDIR   (exit 77: skipped, no pvpython)
set -euo pipefail
FLOWIRE=$1 PVPYTHON=$2 WORK=$3
HERE=$(cd "$(dirname "$0")" && pwd)
if [ -z "$PVPYTHON" ] || [ "$PVPYTHON" = "PVPYTHON-NOTFOUND" ] || ! [ -x "$PVPYTHON" ]; then
  echo "skipped: pvpython not found (ParaView's Python; configure with -DFLOWIRE_PVPYTHON=/path/to/pvpython)"
  exit 77
fi
rm -rf "$WORK" && mkdir -p "$WORK"
"$FLOWIRE" run "$HERE/../../examples/branch_selection/scene.yaml" --out "$WORK/run" \
  --set solve.duration=0.3s --set output.every=0.1s --set output.png=false >/dev/null
test -f "$WORK/run/view.py"
# ParaView 5.11's X window sometimes fails to open its display on a virtual X server ("bad
# X server connection", then SIGABRT, before any check ran): that start is retried.
for attempt in 1 2 3 4 5; do
  rc=0
  "$PVPYTHON" --force-offscreen-rendering "$HERE/check_view.py" "$WORK/run" "$WORK/view.png" >"$WORK/pvpython.log" 2>&1 || rc=$?
  grep -avE '^[[:space:]]*[0-9]+[[:space:]]+0x' "$WORK/pvpython.log" || true
  if [ "$rc" -lt 128 ] || ! grep -aq "bad X server connection" "$WORK/pvpython.log"; then exit "$rc"; fi
  echo "pvpython could not open the X display (attempt $attempt of 5)"
  sleep 2
done
exit 1
