#!/usr/bin/env bash
# An interrupted glint leaves no unfinished file: SIGINT and SIGTERM to `glint run`, SIGHUP to
# `glint points --out`, each while the outputs' temporaries exist, must remove them, say so and
# exit with 128 + the signal's number, and take away the folders the run made and its lock
# file. A SIGKILL cannot be caught: its temporaries are removed by the next glint that writes
# into the same folder, and its lock (a flock) went with the process.
#
# GLINT_TEST_PAUSE_AFTER=temporaries (pipeline/test_pause.h) makes each glint stop once its
# temporaries exist and say so: the signal lands there however fast or loaded the machine is.
# No wait here is timed: a glint that ends without pausing fails the test at once, and one that
# hangs is left to ctest's timeout.
# Usage: interrupt_test.sh GLINT EXAMPLES_DIR WORKDIR
set -uo pipefail
glint=$1 examples=$2 work=$3
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
