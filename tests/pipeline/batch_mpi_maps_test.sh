#!/usr/bin/env bash
# `mpirun -np 2 glint batch` against `glint batch` on one process, on a study of an engagement
# (tests/data/engagement_study.json: the ranks share the scenarios) or one that stops at a
# precision (jitter_mirror_precision.json: the ranks run its rounds together and stop at rank
# 0's word): the study's maps and every scenario's must be the same bytes; scenarios.csv the
# same but for its last column (each scenario's seconds, a wall-clock time).
# Usage: batch_mpi_maps_test.sh GLINT MPIEXEC STUDY WORKDIR
set -euo pipefail
export HWLOC_COMPONENTS=-gl,-opencl  # see batch_mpi_test.sh
glint=$1 mpiexec=$2 study=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
"$glint" batch "$study" -o "$work/one" --threads 2 -q
source "$(dirname "$0")/mpi_ranks.sh"
"$mpiexec" "${ranks[@]}" "$glint" batch "$study" -o "$work/mpi" --threads 1 2> "$work/mpi.log" ||
  { cat "$work/mpi.log" >&2; exit 1; }
cat "$work/mpi.log"
grep -q "on 2 MPI ranks" "$work/mpi.log" || { echo "FAIL: the run did not use 2 ranks" >&2; exit 1; }

maps=$(cd "$work/one" && find . -name '*.exr' | sort)
[ -n "$maps" ] || { echo "FAIL: the study wrote no maps" >&2; exit 1; }
[ "$maps" = "$(cd "$work/mpi" && find . -name '*.exr' | sort)" ] ||
  { echo "FAIL: different maps: $maps" >&2; exit 1; }
for f in $maps; do
  cmp "$work/one/$f" "$work/mpi/$f" || { echo "FAIL: $f differs between 1 and 2 ranks" >&2; exit 1; }
done
strip_seconds() { sed 's/,[^,]*$//' "$1"; }
diff <(strip_seconds "$work/one/scenarios.csv") <(strip_seconds "$work/mpi/scenarios.csv") ||
  { echo "FAIL: scenarios.csv differs between 1 and 2 ranks" >&2; exit 1; }
echo "PASS: 2 ranks wrote the same $(echo $maps | wc -w) maps and scenarios.csv as 1 process"
