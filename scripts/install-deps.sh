#!/usr/bin/env bash
# Installs every Debian 12 package flowire needs to build, test, render and benchmark.
# Idempotent: packages already present are skipped by apt; safe to run repeatedly.
set -euo pipefail

PKGS=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libsuitesparse-dev
  # an optimized BLAS for CHOLMOD (supernodal solves), PETSc and LAPACK; serial: the tests and
  # MPI ranks already use the cores
  libopenblas0-serial
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libvtk9-dev
  petsc-dev openmpi-bin
  libgmsh-dev gmsh
  xvfb xauth
  python3 python3-matplotlib python3-numpy
  python3-dev pybind11-dev python3-pytest
  clang libclang-rt-14-dev clang-format
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
