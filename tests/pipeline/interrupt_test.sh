#!/usr/bin/env bash
# An interrupted glint leaves no unfinished file: SIGINT and SIGTERM to `glint run`, SIGHUP to
# `glint points --out`, each while the outputs' temporaries exist, must remove them, say so and
# exit with 128 + the signal's number, and take away the folders the run made and its lock
# file. A signal that lands between two outputs' moves into place (`glint run` over an earlier
# run's files, `glint points` with its time series, a study's own files) must leave the folder
# as it was. One that lands once every output is in place finds the answer complete: glint says
# so and exits 0, since the folder is no longer as it was. A SIGKILL cannot be caught: its
# temporaries are removed by the next glint that writes into the same folder, and its lock (a
# flock) went with the process.
#
# GLINT_TEST_PAUSE_AFTER=temporaries (pipeline/base/test_pause.h) makes each glint stop once its
# temporaries exist and say so, GLINT_TEST_PAUSE_AFTER=first-output once the first of its
# outputs is in place, GLINT_TEST_PAUSE_AFTER=outputs once all are: the signal lands there
# however fast or loaded the machine is.
# No wait here is timed: a glint that ends without pausing fails the test at once, and one that
# hangs is left to ctest's timeout.
# Usage: interrupt_test.sh GLINT EXAMPLES_DIR WORKDIR TEST_DATA_DIR
set -uo pipefail
glint=$1 examples=$2 work=$3 data=$4
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
# A failed check must not leave a paused glint behind (it would hold ctest's pipe open).
trap 'kill $(jobs -p) 2> /dev/null' EXIT

# await_pause ERR PID DIR: waits until glint PID has written its pause line to ERR, then checks
# that DIR holds its temporaries. A run that ends first makes the test meaningless: say so.
await_pause() {
  until grep -q '^glint: paused after creating the output temporaries' "$1"; do
    kill -0 "$2" 2> /dev/null || fail "the run in $3 ended before it paused: $(tail -2 "$1")"
    sleep 0.05
  done
  compgen -G "$3/.*.glint-$2-*" > /dev/null || fail "glint $2 paused with no temporary in $3"
}

# interrupt SIGNAL STATUS DIR COMMAND...: runs COMMAND, signals it once its temporaries exist,
# and checks the status, the message and the folder.
interrupt() {
  local signal=$1 status=$2 dir=$3
  shift 3
  mkdir -p "$dir"
  GLINT_TEST_PAUSE_AFTER=temporaries "$@" 2> "$dir.err" &
  local pid=$!
  await_pause "$dir.err" "$pid" "$dir"
  kill -s "$signal" "$pid"
  wait "$pid"
  local got=$?
  [ "$got" -eq "$status" ] || fail "$signal: exit status $got, expected $status"
  grep -q "interrupted by SIG$signal; removed [1-9][0-9]* unfinished output file" "$dir.err" ||
    fail "$signal: no message: $(grep -v '^$' "$dir.err" | tail -1)"
  local left
  left=$(find "$dir" -mindepth 1 | head -5)
  [ -z "$left" ] || fail "$signal left files behind: $left"
  echo "$signal: exit $got, folder empty; $(grep interrupted "$dir.err")"
}

scene=$examples/cylinder.json
interrupt INT 130 "$work/int" "$glint" run "$scene" -o "$work/int" --quiet
interrupt TERM 143 "$work/term" "$glint" run "$scene" -o "$work/term" --quiet
interrupt HUP 129 "$work/hup" "$glint" points "$scene" --points "$examples/cylinder_186.csv" \
  --out "$work/hup/out.csv" --quiet

# An interrupted run into folders it made takes them away too, and its folder's lock file.
made=$work/made/deeper
GLINT_TEST_PAUSE_AFTER=temporaries "$glint" run "$scene" -o "$made" --quiet 2> "$work/made.err" &
pid=$!
await_pause "$work/made.err" "$pid" "$made"
[ -f "$made/.glint-lock" ] || fail "the run holds no lock on $made"
kill -s INT "$pid"
wait "$pid"
[ -e "$work/made" ] && fail "an interrupted run left the folders it made: $(find "$work/made" | head -5)"
echo "INT into new folders: $work/made removed"

# SIGKILL: the temporaries stay until the next glint writes into the folder.
mkdir -p "$work/kill"
GLINT_TEST_PAUSE_AFTER=temporaries "$glint" run "$scene" -o "$work/kill" --quiet \
  2> "$work/kill.err" &
pid=$!
await_pause "$work/kill.err" "$pid" "$work/kill"
kill -s KILL "$pid"
wait "$pid" 2> /dev/null
compgen -G "$work/kill/.*.glint-$pid-*" > /dev/null || fail "SIGKILL left no temporaries to test with"
"$glint" run "$examples/disk_glint.json" -o "$work/kill" --quiet || fail "the next run failed"
left=$(compgen -G "$work/kill/.*.glint-*")
[ -z "$left" ] || fail "stale temporaries of the killed run are still there: $left"
[ -f "$work/kill/summary.json" ] || fail "the next run wrote no summary"
echo "KILL: the next run removed the killed run's temporaries"

# Without the variable glint does not pause: the same points run to the end and write the file.
"$glint" points "$scene" --points "$examples/cylinder_186.csv" --out "$work/nopause.csv" \
  --quiet || fail "glint points without GLINT_TEST_PAUSE_AFTER failed"
[ -f "$work/nopause.csv" ] || fail "glint points without GLINT_TEST_PAUSE_AFTER wrote nothing"

# --- A signal between two outputs' moves: the folder as it was before the run.

# snapshot DIR: every entry under DIR, a file with its checksum.
snapshot() {
  (cd "$1" && find . -mindepth 1 | sort | while read -r f; do
    if [ -f "$f" ]; then echo "$f $(md5sum < "$f")"; else echo "$f"; fi
  done)
}

# await_line ERR PID DIR WHAT: waits until glint PID has written "glint: paused after WHAT" to
# ERR; one that ends first fails the test.
await_line() {
  until grep -q "^glint: paused after $4" "$1"; do
    kill -0 "$2" 2> /dev/null || fail "the run in $3 ended before it paused: $(tail -2 "$1")"
    sleep 0.05
  done
}

# between SIGNAL STATUS DIR COMMAND...: runs COMMAND, signals it once its first output is in
# place, and checks the status, the message and that DIR is as it was.
between() {
  local signal=$1 status=$2 dir=$3
  shift 3
  mkdir -p "$dir"
  local before
  before=$(snapshot "$dir")
  GLINT_TEST_PAUSE_AFTER=first-output "$@" 2> "$dir.err" &
  local pid=$!
  await_line "$dir.err" "$pid" "$dir" 'putting the first output in place'
  kill -s "$signal" "$pid"
  wait "$pid"
  local got=$?
  [ "$got" -eq "$status" ] || fail "$signal between outputs: exit status $got, expected $status"
  [ "$(snapshot "$dir")" = "$before" ] ||
    fail "$signal between outputs changed $dir: $(diff <(echo "$before") <(snapshot "$dir") | head -5)"
  grep -q "interrupted by SIG$signal; removed [1-9][0-9]* unfinished output file" "$dir.err" ||
    fail "$signal between outputs: no message: $(grep -v '^$' "$dir.err" | tail -1)"
  echo "$signal between outputs: exit $got, $dir as it was; $(grep interrupted "$dir.err")"
}

# glint run over an earlier run of the same scene: five small files (two coarse planes and a
# coarse far field, about 2 s). The first in place replaced the earlier run's: it comes back.
tiny=$work/tiny.json
cat > "$tiny" << 'EOF'
{
  "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000.0,
            "wavelength_nm": 1064, "exposure_s": 10,
            "beam": {"profile": "flat_top", "radius_m": 2.0}},
  "materials": {"polished": {"specular_reflectance": 0.9, "sigma": 0.003}},
  "objects": [{"shape": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.5,
               "length": 2.0, "material": "polished"}],
  "planes": [
    {"name": "first", "origin": [-10, -10, 0.5], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
     "size_m": [20, 20], "pixel_m": 0.5, "block_m": 4},
    {"name": "second", "origin": [-10, -10, 0], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
     "size_m": [20, 20], "pixel_m": 0.5, "block_m": 4}],
  "far_field": {"face_pixels": 32}
}
EOF
"$glint" run "$tiny" -o "$work/between_run" --quiet || fail "the earlier run failed"
between TERM 143 "$work/between_run" "$glint" run "$tiny" -o "$work/between_run" --quiet
grep -q "and put back 1 earlier one(s)" "$work/between_run.err" ||
  fail "the earlier file the first output replaced was not put back: $(grep interrupted "$work/between_run.err")"

# glint points: the table in place, the time series not yet.
between INT 130 "$work/between_points" "$glint" points "$data/engagement_mpi.json" \
  --points "$data/engagement_points.csv" --out "$work/between_points/table.csv" \
  --time-series "$work/between_points/series.csv" --quiet

# glint batch: the study's scenarios.csv in place, its maps and summary.json not yet; the
# finished scenario stays, and the next run takes it up. (The study's files of a first run are
# removed so that the interrupted run is the one that writes them.)
study=$work/between_study
mkdir -p "$study"
sed -e 's/"voxel_m": 0.4/"voxel_m": 0.8/' -e 's/"pixel_m": 0.2/"pixel_m": 0.4/' \
  "$data/study_scene.json" > "$study/base.json"
echo '{"scene": "base.json", "sweep": {"pitch_deg": [4]}}' > "$study/study.json"
"$glint" batch "$study/study.json" -o "$study/out" --quiet || fail "the study's first run failed"
rm "$study/out/scenarios.csv" "$study/out/box.vdb" "$study/out/ground.exr" "$study/out/summary.json"
between HUP 129 "$study/out" "$glint" batch "$study/study.json" -o "$study/out" --quiet
"$glint" batch "$study/study.json" -o "$study/out" 2> "$study/resumed.err" ||
  fail "the study did not resume: $(tail -2 "$study/resumed.err")"
grep -q "(1 done before, 0 to run)" "$study/resumed.err" ||
  fail "the study did not take its finished scenario up: $(head -2 "$study/resumed.err")"
echo "batch: resumed its finished scenario after the interrupt"

# after SIGNAL DIR FILE... COMMAND: runs COMMAND, signals it once every output is in place, and
# checks that it says so and exits 0 (not "as it was": the folder holds the new outputs), with
# each FILE present and newer than the command's start.
after() {
  local signal=$1 dir=$2
  shift 2
  local files=()
  while [ "$1" != "--" ]; do files+=("$1"); shift; done
  shift
  mkdir -p "$dir"
  touch "$dir.start"
  sleep 1  # the outputs' times must be told apart from the start's at one second's resolution
  GLINT_TEST_PAUSE_AFTER=outputs "$@" 2> "$dir.err" &
  local pid=$!
  await_line "$dir.err" "$pid" "$dir" 'putting every output in place'
  kill -s "$signal" "$pid"
  wait "$pid"
  local got=$?
  [ "$got" -eq 0 ] || fail "$signal after the outputs: exit status $got, expected 0 (they are complete)"
  grep -q "interrupted by SIG$signal after its outputs were in place: they are complete" "$dir.err" ||
    fail "$signal after the outputs: no message: $(grep -v '^$' "$dir.err" | tail -1)"
  for f in "${files[@]}"; do
    [ "$dir/$f" -nt "$dir.start" ] || fail "$signal after the outputs: $dir/$f is not the new output"
  done
  echo "$signal after the outputs: exit 0, outputs in place; $(grep interrupted "$dir.err")"
}

after TERM "$work/after_run" first.exr second.exr far_field.exr summary.json -- \
  "$glint" run "$tiny" -o "$work/after_run" --quiet
after INT "$work/after_points" table.csv series.csv -- "$glint" points "$data/engagement_mpi.json" \
  --points "$data/engagement_points.csv" --out "$work/after_points/table.csv" \
  --time-series "$work/after_points/series.csv" --quiet
