#!/usr/bin/env bash
# `mpirun -np 2 glint batch` against `glint batch` on one process: the aggregated maps must be
# the same bytes, and scenarios.csv the same but for its last column (each scenario's seconds,
# a wall-clock time). Also reads box.vdb back with OpenVDB's Python module, and checks that a
# job into a folder another process holds is refused.
# Usage: batch_mpi_test.sh GLINT MPIEXEC STUDY SERIAL_RUN_DIR WORKDIR
# (SERIAL_RUN_DIR: the study run on one process, by the ctest fixture GlintBatch.RunsTheTestStudy)
set -euo pipefail
# Open MPI's hwloc would otherwise open every X display it finds (looking for GPUs), which
# can upset a virtual display another test is using at the same time.
export HWLOC_COMPONENTS=-gl,-opencl
glint=$1 mpiexec=$2 study=$3 serial=$4 work=$5
rm -rf "$work" && mkdir -p "$work"
# As root, Open MPI needs --allow-run-as-root; --oversubscribe lets 2 ranks start on any machine.
# Each rank takes one thread, so the two ranks share the cores instead of fighting over them.
"$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$glint" batch "$study" -o "$work/mpi" \
  --threads 1 2> "$work/mpi.log" || { cat "$work/mpi.log" >&2; exit 1; }
cat "$work/mpi.log"
grep -q "on 2 MPI ranks" "$work/mpi.log" || { echo "FAIL: the run did not use 2 ranks" >&2; exit 1; }

for f in ground.exr box.vdb; do
  cmp "$serial/$f" "$work/mpi/$f" || { echo "FAIL: $f differs between 1 and 2 ranks" >&2; exit 1; }
done
strip_seconds() { sed 's/,[^,]*$//' "$1"; }
diff <(strip_seconds "$serial/scenarios.csv") <(strip_seconds "$work/mpi/scenarios.csv") ||
  { echo "FAIL: scenarios.csv differs between 1 and 2 ranks" >&2; exit 1; }
[ "$(wc -l < "$work/mpi/scenarios.csv")" -eq 5 ] || { echo "FAIL: not 4 scenario rows" >&2; exit 1; }

/usr/bin/python3 - "$work/mpi/box.vdb" <<'PY'
import sys, pyopenvdb as vdb
grids = {g.name: g for g in vdb.readAll(sys.argv[1])[0]}
assert set(grids) == {"max_irradiance_w_m2", "max_hazard_ratio", "coverage_probability",
                      "coverage_lower", "coverage_upper"}, grids
lo, hi = grids["coverage_probability"].evalMinMax()
assert 0.0 <= lo and hi <= 1.0 and hi > 0.0, (lo, hi)
# The Clopper-Pearson ends lie in [0, 1].
assert grids["coverage_upper"].evalMinMax()[1] <= 1.0 and grids["coverage_lower"].evalMinMax()[0] >= 0.0
print("box.vdb: grids", sorted(grids), "coverage in", (lo, hi))
PY

# A folder another glint holds (here flock(1) with a glint-style lock file) is refused by rank 0
# for the whole job: exit status 2, the holder named, nothing written.
mkdir -p "$work/held"
printf 'pid=%d\nhost=%s\n' $$ "$(hostname)" > "$work/held/.glint-lock"
status=0
flock -n "$work/held/.glint-lock" "$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$glint" \
  batch "$study" -o "$work/held" --threads 1 2> "$work/held.log" || status=$?
[ "$status" -eq 2 ] || { cat "$work/held.log" >&2; echo "FAIL: a held folder gave exit $status, not 2" >&2; exit 1; }
grep -q "held is in use by glint process $$ on host" "$work/held.log" ||
  { cat "$work/held.log" >&2; echo "FAIL: the refusal does not name the holder" >&2; exit 1; }
[ "$(ls -A "$work/held")" = ".glint-lock" ] ||
  { ls -A "$work/held" >&2; echo "FAIL: the refused job wrote into the held folder" >&2; exit 1; }
echo "PASS: 2 ranks gave the same maps and table as 1 process; a held folder was refused"
