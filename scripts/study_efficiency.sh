#!/usr/bin/env bash
# How well `flowire study` shares runs out (docs/study.md, "Speed"): writes two CSV tables.
#   OUT/efficiency.csv  a 32-run study of the aortic arch (runs of 1 s of simulated time) on one
#                       rank with one job, on 2 MPI ranks and with --jobs 2: runs per second and
#                       the parallel efficiency, (runs/s on N slots) / (N × runs/s on one)
#   OUT/dispatch.csv    what rank 0's dispatching costs per run, from a 64-run study of trivial
#                       runs (one step of a small tube): CPU time of its dispatching thread and
#                       the wall time it spent handling requests, per run handed out
# The times are the studies' own (study.json: the sessions' dispatch), from the first run handed
# out to the last result: launcher start-up and the study file's checks are not in them. Each
# setup runs REPEAT times (default 3) and the fastest counts: other work on the machine only
# ever slows a study down.
# usage: scripts/study_efficiency.sh [OUT_DIR]   (FLOWIRE=path/to/flowire, MPIEXEC=mpiexec, REPEAT=3)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
OUT=${1:-out/study_efficiency}
FLOWIRE=${FLOWIRE:-$root/build/tools/flowire}
MPIEXEC=${MPIEXEC:-$(command -v mpiexec || true)}
REPEAT=${REPEAT:-3}
PY=/usr/bin/python3
# Open MPI as root and with more ranks than cores; other launchers ignore these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

cat >"$OUT/runs32.yaml" <<EOF
scene: $root/examples/aortic_arch/scene.yaml
set: {solve.duration: 1 s, output.vtk: false}
parameters:
  insertion.speed: {from: 1 cm/s, to: 2 cm/s, count: 4}
  coupling.drag: [cylinder, none]
  insertion.rotation_angle: [0 deg, 45 deg, 90 deg, 135 deg]
collect:
  inserted: {summary: wire.inserted_length}
keep_runs: false
plot: false
EOF
cat >"$OUT/tube.yaml" <<'EOF'
vessels: {generator: {type: straight_tube, length: 20 mm, radius: 2 mm}}
flow: {inlet: {pressure: 100 Pa}, outlets: {pressure: 0}}
solve: {dt: 1 ms, duration: 1 ms}
output: {vtk: false}
EOF
cat >"$OUT/trivial64.yaml" <<'EOF'
scene: tube.yaml
parameters:
  flow.inlet.pressure: {from: 100 Pa, to: 6400 Pa, count: 64}
collect:
  steps: {summary: steps}
keep_runs: false
plot: false
EOF

# study NAME STUDY RANKS JOBS: run a study (under the launcher when RANKS > 0) REPEAT times;
# the fastest is kept as OUT/NAME.
study() {
  local name=$1 file=$2 ranks=$3 jobs=$4 r
  rm -rf "${OUT:?}/$name"
  for r in $(seq "$REPEAT"); do
    rm -rf "${OUT:?}/$name.try"
    if [ "$ranks" -gt 0 ]; then
      "$MPIEXEC" -n "$ranks" "$FLOWIRE" study "$OUT/$file" --out "$OUT/$name.try" --jobs "$jobs" >/dev/null
    else
      "$FLOWIRE" study "$OUT/$file" --out "$OUT/$name.try" --jobs "$jobs" >/dev/null
    fi
    if [ ! -d "$OUT/$name" ] || "$PY" -c "import sys; sys.exit(0 if float(sys.argv[1]) < float(sys.argv[2]) else 1)" \
      "$(session "$name.try" wall_seconds)" "$(session "$name" wall_seconds)"; then
      rm -rf "${OUT:?}/$name"
      mv "$OUT/$name.try" "$OUT/$name"
    fi
  done
  rm -rf "${OUT:?}/$name.try"
}
# session NAME FIELD: a number of the study's last session's dispatch record.
session() { "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['sessions'][-1]['dispatch'][sys.argv[2]])" "$OUT/$1/study.json" "$2"; }

echo "setup,ranks,jobs,runs,seconds,runs_per_second,efficiency" >"$OUT/efficiency.csv"
study one runs32.yaml 0 1
t1=$(session one wall_seconds)
row() {  # row SETUP RANKS JOBS NAME
  local t slots
  t=$(session "$4" wall_seconds)
  slots=$(($2 * $3))
  "$PY" -c "import sys; t,t1,n=float(sys.argv[1]),float(sys.argv[2]),int(sys.argv[3]); print(f'$1,$2,$3,32,{t:.3f},{32/t:.3f},{t1/(n*t):.3f}')" "$t" "$t1" "$slots" >>"$OUT/efficiency.csv"
}
row "one rank --jobs 1" 1 1 one
study jobs2 runs32.yaml 0 2
row "one rank --jobs 2" 1 2 jobs2
if [ -n "$MPIEXEC" ]; then
  study ranks2 runs32.yaml 2 1
  row "mpiexec -n 2" 2 1 ranks2
fi

echo "setup,ranks,jobs,runs,rank0_cpu_seconds_per_run,rank0_handling_seconds_per_run,wakeups_per_run,runs_per_second" \
  >"$OUT/dispatch.csv"
drow() {  # drow SETUP RANKS JOBS NAME
  "$PY" - "$OUT/$4/study.json" "$1" "$2" "$3" >>"$OUT/dispatch.csv" <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))["sessions"][-1]["dispatch"]
n = d["runs"]
print(f"{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{n},{d['cpu_seconds']/n:.3e},{d['handling_seconds']/n:.3e},"
      f"{d['wakeups']/n:.1f},{n/d['wall_seconds']:.2f}")
PYEOF
}
study trivial_jobs2 trivial64.yaml 0 2
drow "one rank --jobs 2" 1 2 trivial_jobs2
if [ -n "$MPIEXEC" ]; then
  study trivial_ranks2 trivial64.yaml 2 1
  drow "mpiexec -n 2" 2 1 trivial_ranks2
  study trivial_ranks4 trivial64.yaml 4 1
  drow "mpiexec -n 4 (oversubscribed)" 4 1 trivial_ranks4
fi
column -s, -t <"$OUT/efficiency.csv"
echo
column -s, -t <"$OUT/dispatch.csv"
echo "tables: $OUT/efficiency.csv, $OUT/dispatch.csv"
