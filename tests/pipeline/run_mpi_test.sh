#!/usr/bin/env bash
# `mpirun -np 2 glint run` against `glint run` on one process (tests/data/run_mpi.json: a box, a
# plane, the far field and the hazard reach; engagement_mpi.json: an engagement over a box and a
# plane): every file must be the same bytes, but for the VDB's grid UUIDs (random per write) and
# summary.json's "seconds", "wall_seconds" and "outside_phases_seconds" (wall-clock times).
# Usage: run_mpi_test.sh GLINT MPIEXEC SCENE WORKDIR
set -euo pipefail
export HWLOC_COMPONENTS=-gl,-opencl  # see batch_mpi_test.sh
glint=$1 mpiexec=$2 scene=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
"$glint" run "$scene" -o "$work/one" --threads 2 -q
source "$(dirname "$0")/mpi_ranks.sh"
"$mpiexec" "${ranks[@]}" "$glint" run "$scene" -o "$work/mpi" --threads 1 2> "$work/mpi.log" ||
  { cat "$work/mpi.log" >&2; exit 1; }
cat "$work/mpi.log"
grep -q "2 MPI ranks share" "$work/mpi.log" || { echo "FAIL: the run did not use 2 ranks" >&2; exit 1; }

files=$(cd "$work/one" && ls)
[ "$files" = "$(cd "$work/mpi" && ls)" ] || { echo "FAIL: different files: $files" >&2; exit 1; }
for f in $files; do
  case $f in
    irradiance.vdb|engagement.vdb)  # the same grids and metadata, once the UUIDs are blanked
      for d in one mpi; do
        /usr/bin/python3 - "$work/$d/$f" "$work/$d/$f.blank" <<'PY'
import re, sys
data = open(sys.argv[1], "rb").read()
# Each grid descriptor carries a 36-character UUID, random per write.
blank = re.sub(rb"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", b"U" * 36, data)
open(sys.argv[2], "wb").write(blank)
PY
      done
      cmp "$work/one/$f.blank" "$work/mpi/$f.blank" ||
        { echo "FAIL: $f differs between 1 and 2 ranks" >&2; exit 1; } ;;
    summary.json)
      diff <(grep -vE '"([a-z_]+_)?seconds"' "$work/one/$f") <(grep -vE '"([a-z_]+_)?seconds"' "$work/mpi/$f") ||
        { echo "FAIL: $f differs between 1 and 2 ranks" >&2; exit 1; } ;;
    irradiance)  # the AMR's blocks (irradiance.vthb names them)
      diff -r "$work/one/$f" "$work/mpi/$f" > /dev/null ||
        { echo "FAIL: $f/ differs between 1 and 2 ranks" >&2; exit 1; } ;;
    *)
      cmp "$work/one/$f" "$work/mpi/$f" ||
        { echo "FAIL: $f differs between 1 and 2 ranks" >&2; exit 1; } ;;
  esac
done
echo "PASS: 2 ranks wrote the same $(echo $files | wc -w) files as 1 process"
