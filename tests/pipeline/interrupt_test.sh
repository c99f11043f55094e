#!/usr/bin/env bash
# An interrupted glint leaves no unfinished file: SIGINT and SIGTERM to `glint run`, SIGHUP to
# `glint points --out`, each while the outputs' temporaries exist, must remove them, say so and
# exit with 128 + the signal's number. A SIGKILL cannot be caught: its temporaries are removed
# by the next glint that writes into the same folder.
# Usage: interrupt_test.sh GLINT EXAMPLES_DIR WORKDIR
set -uo pipefail
glint=$1 examples=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }

# await_temporaries DIR PID: waits (up to 60 s) until DIR holds a glint temporary, i.e. the run
# has opened its outputs. A run that ends first makes the test meaningless: say so at once.
await_temporaries() {
  for _ in $(seq 600); do
    compgen -G "$1/.*.glint-*" > /dev/null && return 0
    kill -0 "$2" 2> /dev/null || fail "the run in $1 ended before it could be signalled"
    sleep 0.1
  done
  fail "no temporary appeared in $1"
}

# interrupt SIGNAL STATUS DIR COMMAND...: runs COMMAND, signals it once its temporaries exist,
# and checks the status, the message and the folder.
interrupt() {
  local signal=$1 status=$2 dir=$3
  shift 3
  mkdir -p "$dir"
  "$@" 2> "$dir.err" &
  local pid=$!
  await_temporaries "$dir" "$pid"
  kill -s "$signal" "$pid"
  wait "$pid"
  local got=$?
  [ "$got" -eq "$status" ] || fail "$signal: exit status $got, expected $status"
  grep -q "interrupted by SIG$signal; removed [1-9][0-9]* unfinished output file" "$dir.err" ||
    fail "$signal: no message: $(tail -2 "$dir.err")"
  local left
  left=$(find "$dir" -mindepth 1 | head -5)
  [ -z "$left" ] || fail "$signal left files behind: $left"
  echo "$signal: exit $got, folder empty; $(grep interrupted "$dir.err")"
}

scene=$examples/cylinder.json  # minutes of work: certainly still running when signalled
interrupt INT 130 "$work/int" "$glint" run "$scene" -o "$work/int" --quiet
interrupt TERM 143 "$work/term" "$glint" run "$scene" -o "$work/term" --quiet
# The 186 observers take a fraction of a second: repeat them until the run lasts minutes.
many_points=$work/many_points.csv
head -1 "$examples/cylinder_186.csv" > "$many_points"
for _ in $(seq 2000); do tail -n +2 "$examples/cylinder_186.csv"; done >> "$many_points"
interrupt HUP 129 "$work/hup" "$glint" points "$scene" --points "$many_points" \
  --out "$work/hup/out.csv" --quiet

# SIGKILL: the temporaries stay until the next glint writes into the folder.
mkdir -p "$work/kill"
"$glint" run "$scene" -o "$work/kill" --quiet 2> /dev/null &
pid=$!
await_temporaries "$work/kill" "$pid"
kill -s KILL "$pid"
wait "$pid" 2> /dev/null
compgen -G "$work/kill/.*.glint-$pid-*" > /dev/null || fail "SIGKILL left no temporaries to test with"
"$glint" run "$examples/disk_glint.json" -o "$work/kill" --quiet || fail "the next run failed"
left=$(compgen -G "$work/kill/.*.glint-*")
[ -z "$left" ] || fail "stale temporaries of the killed run are still there: $left"
[ -f "$work/kill/summary.json" ] || fail "the next run wrote no summary"
echo "KILL: the next run removed the killed run's temporaries"
