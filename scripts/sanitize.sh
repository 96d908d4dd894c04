#!/usr/bin/env bash
# The sanitizer check, the habit before stopping work on code that handles memory:
# 1. configure with the `debug` preset (AddressSanitizer + UBSan) in build-sanitize, build,
#    and run the default tests there (third-party leaks are suppressed by
#    tools/sanitizers/lsan.supp; a leak from flowire's own code or any UBSan error fails);
# 2. build the libFuzzer targets (preset `fuzz`, clang) in build-sanitize-fuzz and run each
#    for a fixed time (30 s by default).
# Usage: scripts/sanitize.sh [--fuzz-seconds N] [--no-fuzz] [--jobs N]   (NICE=n: build niceness, 10)
set -euo pipefail
cd "$(dirname "$0")/.."

FUZZ_SECONDS=30
FUZZ=1
JOBS=$(nproc)
while [ $# -gt 0 ]; do
  case "$1" in
    --fuzz-seconds) FUZZ_SECONDS=${2:?--fuzz-seconds needs a number}; shift 2 ;;
    --no-fuzz) FUZZ=0; shift ;;
    -j | --jobs) JOBS=${2:?--jobs needs a number}; shift 2 ;;
    -h | --help) sed -n '2,8p' "$0"; exit 0 ;;
    *) echo "sanitize.sh: error: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if ! [[ "$FUZZ_SECONDS" =~ ^[1-9][0-9]*$ ]]; then
  echo "sanitize.sh: error: --fuzz-seconds: '$FUZZ_SECONDS' is not a positive whole number" >&2
  exit 2
fi

bash scripts/install-deps.sh
LAUNCHER=()
if command -v ccache >/dev/null; then
  LAUNCHER=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Paths relative to the folder above the checkout: worktrees share the cache.
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$PWD")}
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
start=$SECONDS

cmake --preset debug -B build-sanitize "${LAUNCHER[@]}" >/dev/null
nice -n "${NICE:-10}" cmake --build build-sanitize -j"$JOBS"
# Under a virtual X server when there is one, so the VTK rendering tests run too.
XR=()
if command -v xvfb-run >/dev/null; then XR=(xvfb-run -a -s "-screen 0 1024x768x24"); fi
"${XR[@]}" ctest --test-dir build-sanitize -LE "slow|stress" --output-on-failure -j"$JOBS" --timeout 600
echo "sanitize.sh: the default tests pass under AddressSanitizer + UBSan ($((SECONDS - start)) s so far)"

if [ "$FUZZ" = 1 ]; then
  cmake --preset fuzz -B build-sanitize-fuzz "${LAUNCHER[@]}" -DFLOWIRE_WITH_TESTS=ON \
    -DFLOWIRE_WITH_BENCHMARKS=OFF -DFLOWIRE_FUZZ_SECONDS="$FUZZ_SECONDS" >/dev/null
  nice -n "${NICE:-10}" cmake --build build-sanitize-fuzz -j"$JOBS" --target fuzzers
  ctest --test-dir build-sanitize-fuzz -L fuzz --output-on-failure
  echo "sanitize.sh: the fuzz targets ran $FUZZ_SECONDS s each without a finding"
fi
echo "sanitize.sh: clean in $((SECONDS - start)) s"
