#!/usr/bin/env bash
# `mpirun -np 2 glint points` against `glint points` on one process: the ranks share the
# observers, and the table (and, over an engagement, the time series) must be the same bytes.
# Usage: points_mpi_test.sh GLINT MPIEXEC WORKDIR SCENE POINTS [SCENE POINTS ...]
set -euo pipefail
export HWLOC_COMPONENTS=-gl,-opencl  # see batch_mpi_test.sh
glint=$1 mpiexec=$2 work=$3
shift 3
rm -rf "$work" && mkdir -p "$work"
source "$(dirname "$0")/mpi_ranks.sh"
n=0
while [ $# -ge 2 ]; do
  scene=$1 points=$2
  shift 2
  n=$((n + 1))
  # Over an engagement, each observer's time series too.
  engagement=0
  grep -q '"engagement"' "$scene" && engagement=1
  one=() mpi=()
  if [ $engagement = 1 ]; then
    one=(--time-series "$work/$n.one.series") mpi=(--time-series "$work/$n.mpi.series")
  fi
  "$glint" points "$scene" --points "$points" -o "$work/$n.one.csv" --threads 2 -q \
    ${one[@]+"${one[@]}"}
  "$mpiexec" "${ranks[@]}" "$glint" points "$scene" --points "$points" -o "$work/$n.mpi.csv" \
    --threads 1 ${mpi[@]+"${mpi[@]}"} 2> "$work/$n.log" || { cat "$work/$n.log" >&2; exit 1; }
  cat "$work/$n.log"
  grep -q "2 MPI ranks share the observers" "$work/$n.log" ||
    { echo "FAIL: $scene did not use 2 ranks" >&2; exit 1; }
  cmp "$work/$n.one.csv" "$work/$n.mpi.csv" ||
    { echo "FAIL: $scene: the table differs between 1 and 2 ranks" >&2; exit 1; }
  if [ $engagement = 1 ]; then
    cmp "$work/$n.one.series" "$work/$n.mpi.series" ||
      { echo "FAIL: $scene: the time series differs between 1 and 2 ranks" >&2; exit 1; }
  fi
  echo "PASS: $scene: 2 ranks wrote the same $(($(wc -l < "$work/$n.one.csv") - 1)) rows as 1 process"
done
