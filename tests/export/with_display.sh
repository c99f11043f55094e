#!/usr/bin/env bash
# Runs a command on a fresh virtual X display. Xvfb picks a free display number itself and
# writes it to a pipe once it accepts connections (-displayfd), so the client never connects
# before the server is up.
#
# Even so, under load (ctest -j beside CPU-heavy tests) ParaView's XOpenDisplay fails now and
# then ("bad X server connection") with the server alive and its log empty; not understood.
# That one failure, and only that one, is retried on a new server, at most three times.
set -uo pipefail
log=$(mktemp)
trap 'rm -f "$log"' EXIT
for attempt in 1 2 3; do
  fifo=$(mktemp -u)
  mkfifo "$fifo"
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$fifo" 2>/dev/null &
  xvfb=$!
  read -r display <"$fifo"
  rm -f "$fifo"
  DISPLAY=":$display" "$@" 2> >(tee "$log" >&2)
  status=$?
  kill "$xvfb" 2>/dev/null
  wait "$xvfb" 2>/dev/null
  if [ "$status" -eq 0 ] || ! grep -q "bad X server connection" "$log"; then exit "$status"; fi
  echo "with_display.sh: attempt $attempt lost its X connection; retrying on a new server" >&2
done
exit "$status"
