#!/usr/bin/env bash
# Install dependencies, build flowire and run the default test suite (everything not
# labelled slow or stress). Usage: scripts/test.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
bash scripts/install-deps.sh
cmake --preset default -B "$BUILD" >/dev/null
cmake --build "$BUILD" -j"$(nproc)"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Under a virtual X server when there is one, so the VTK rendering tests run too.
XR=()
if command -v xvfb-run >/dev/null; then XR=(xvfb-run -a -s "-screen 0 1024x768x24"); fi
"${XR[@]}" ctest --test-dir "$BUILD" -LE "slow|stress" --output-on-failure -j"$(nproc)" --timeout 600
