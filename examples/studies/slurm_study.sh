#!/usr/bin/env bash
# A flowire study as a SLURM batch job (docs/study.md, "On a cluster"). One MPI rank per core:
# rank 0 hands the runs out and runs its share, every rank runs one `flowire run` at a time.
# The study resumes where it stopped, so the same script is resubmitted as it is after a time
# limit, a lost node or scancel: only the runs without a result run again.
#
#   sbatch examples/studies/slurm_study.sh examples/studies/flow_on_off.yaml out/flow_on_off
#
# The output folder must be on a file system every node sees (the runs write there, rank 0
# reads their results). Adapt the #SBATCH lines to the cluster (partition, account).
#SBATCH --job-name=flowire-study
#SBATCH --nodes=2
#SBATCH --ntasks-per-node=32
#SBATCH --cpus-per-task=1
#SBATCH --time=02:00:00
#SBATCH --signal=TERM@120
#SBATCH --requeue
#SBATCH --output=flowire-study-%j.log
set -euo pipefail
STUDY=${1:?usage: sbatch slurm_study.sh STUDY.yaml OUT_DIR}
OUT=${2:?usage: sbatch slurm_study.sh STUDY.yaml OUT_DIR}
FLOWIRE=${FLOWIRE:-flowire}   # installed: <prefix>/bin/flowire; or build/tools/flowire

# Each run is a process of its own: one thread each keeps the cores to the runs.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1

# srun starts the ranks (Open MPI and MPICH built with SLURM support read its PMI/PMIx);
# `mpirun -n "$SLURM_NTASKS"` works as well. On SIGTERM (the time limit, 120 s early by
# --signal, or scancel) the ranks end their runs and leave the finished results in place.
status=0
srun --kill-on-bad-exit=1 "$FLOWIRE" study "$STUDY" --out "$OUT" --jobs 1 || status=$?

# Done: study.json says "done". Otherwise (interrupted, or runs that a lost node took with it)
# the job puts itself back in the queue; the next start runs only what is missing.
if ! grep -q '"status": "done"' "$OUT/study.json" 2>/dev/null; then
  echo "flowire study: not finished (exit status $status); requeueing job $SLURM_JOB_ID"
  scontrol requeue "$SLURM_JOB_ID"
fi
exit "$status"
