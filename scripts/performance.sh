#!/usr/bin/env bash
# Build flowire_bench, run every study into out/performance/, draw the figures and
# generate docs/performance.md (+ docs/performance/*.png).
#   bash scripts/performance.sh            # full size (about 20-30 min on 2 cores)
#   bash scripts/performance.sh --quick    # reduced size (a few minutes)
# Environment: BUILD_DIR (default build-bench), OUT_DIR (default out/performance),
# JOBS (default 2), PYTHON (default /usr/bin/python3, Debian's, with matplotlib).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
MODE=full
SIZE_FLAG=()
for a in "$@"; do
  case "$a" in
    --quick) MODE=quick; SIZE_FLAG=(--reduced) ;;
    -h|--help) sed -n 2,8p "$0"; exit 0 ;;
    *) echo "performance.sh: unknown option $a" >&2; exit 2 ;;
  esac
done
BUILD_DIR=${BUILD_DIR:-$ROOT/build-bench}
OUT_DIR=${OUT_DIR:-$ROOT/out/performance}
JOBS=${JOBS:-2}
PYTHON=${PYTHON:-/usr/bin/python3}

if [ ! -f "$BUILD_DIR/build.ninja" ] && [ ! -f "$BUILD_DIR/Makefile" ]; then
  cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFLOWIRE_WITH_FEM=ON
else
  cmake -S "$ROOT" -B "$BUILD_DIR" -DFLOWIRE_WITH_FEM=ON >/dev/null
fi
cmake --build "$BUILD_DIR" --target flowire_bench bench_coupling -j"$JOBS"
BENCH="$BUILD_DIR/tools/bench/flowire_bench"

rm -rf "$OUT_DIR"
mkdir -p "$OUT_DIR/figures"
: > "$OUT_DIR/commands.tsv"
run_study() {  # name, then the flowire_bench arguments
  local name=$1; shift
  local t0 rc=0
  t0=$(date +%s.%N)
  "$BENCH" "$@" --out "$OUT_DIR" "${SIZE_FLAG[@]}" > "$OUT_DIR/$name.stdout" 2> "$OUT_DIR/$name.log" || rc=$?
  printf '%s\t%s\t%s\t%.1f\n' "$name" "flowire_bench $* --out $OUT_DIR ${SIZE_FLAG[*]}" "$rc" \
    "$(echo "$(date +%s.%N) - $t0" | bc)" >> "$OUT_DIR/commands.tsv"
  echo "performance.sh: $name exit $rc" >&2
}
run_study rod rod-work-precision
run_study flow flow-frame-cost
run_study flowfem flow-fem-work-precision   # exit 2 (no figure) in a build without FEM
run_study cosim cosim-work-precision
run_study features feature-cost
run_study stress stress   # exit 1 when a point fails: reported in the note, not hidden
# The co-simulation step by phase (Google Benchmark, JSON).
"$BUILD_DIR/bench/bench_coupling" --benchmark_filter=ArchExample --benchmark_format=json \
  > "$OUT_DIR/coupling_phases.json" 2> "$OUT_DIR/coupling_phases.log" || echo "performance.sh: bench_coupling failed" >&2

for p in rod flow cosim stress; do
  "$PYTHON" "$ROOT/tools/bench/plot_$p.py" "$OUT_DIR" "$OUT_DIR/figures"
done
"$PYTHON" "$ROOT/tools/bench/make_report.py" "$OUT_DIR" "$ROOT/docs" "$MODE"
echo "performance.sh: wrote $ROOT/docs/performance.md" >&2
