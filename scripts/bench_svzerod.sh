#!/usr/bin/env bash
# flowire against svZeroDSolver on the same svZeroDSolver models, one after the other:
# whole-process wall time and peak memory (/usr/bin/time -v) as CSV on stdout.
#
#   SVZERODSOLVER=/path/to/svzerodsolver scripts/bench_svzerod.sh [SIZE...]   # sizes: 300 2500 25000
#
# The models are written by ../shared/peers/svzerod-trees/gen_svzerod_trees.py into a
# temporary directory (tree_<SIZE>_meanonly.json). Without SVZERODSOLVER (or when it is not
# executable) the peer is skipped, and the script says so on stderr. FLOWIRE defaults to
# build/tools/flowire; GENERATOR to the generator script beside the project.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
flowire="${FLOWIRE:-$here/build/tools/flowire}"
generator="${GENERATOR:-$here/../shared/peers/svzerod-trees/gen_svzerod_trees.py}"
peer="${SVZERODSOLVER:-}"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(300 2500)
[ -x /usr/bin/time ] || { echo "bench_svzerod: needs GNU time (apt-get install time)" >&2; exit 2; }
[ -x "$flowire" ] || { echo "bench_svzerod: no flowire at $flowire (build it, or set FLOWIRE)" >&2; exit 2; }
[ -f "$generator" ] || { echo "bench_svzerod: no generator at $generator (set GENERATOR)" >&2; exit 2; }
if [ -z "$peer" ] || [ ! -x "$peer" ]; then
  echo "bench_svzerod: SVZERODSOLVER is not set to an executable svzerodsolver: the peer is skipped" >&2
  peer=""
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/models"
python3 "$generator" "$work/models" >/dev/null

# measure NAME CMD... : one CSV row "code,model,seconds,peak_mib"
measure() {
  local code="$1" model="$2"
  shift 2
  /usr/bin/time -v -o "$work/time.txt" "$@" >"$work/stdout.txt" 2>"$work/stderr.txt" || {
    echo "bench_svzerod: $code failed on $model:" >&2
    cat "$work/stderr.txt" >&2
    exit 3
  }
  awk -v code="$code" -v model="$model" '
    /Elapsed \(wall clock\)/ { n = split($NF, p, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + p[i] }
    /Maximum resident set size/ { kb = $NF }
    END { printf "%s,%s,%.3f,%.1f\n", code, model, s, kb / 1024 }' "$work/time.txt"
}

echo "code,model,seconds,peak_mib"
for n in "${sizes[@]}"; do
  model="$work/models/tree_${n}_meanonly.json"
  [ -f "$model" ] || { echo "bench_svzerod: the generator wrote no $model" >&2; exit 2; }
  measure flowire "tree_${n}_meanonly" "$flowire" run "$model" --out "$work/out_flowire_$n"
  if [ -n "$peer" ]; then
    measure svzerodsolver "tree_${n}_meanonly" "$peer" "$model" "$work/out_peer_$n.csv"
  fi
done
