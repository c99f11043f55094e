#!/usr/bin/env bash
# Runs a command on a fresh virtual X display. Xvfb picks a free display number itself and
# writes it to a pipe once it accepts connections (-displayfd), so the client never connects
# before the server is up.
#
# Why -noreset and HWLOC_COMPONENTS: Debian's pvpython starts Open MPI, whose hwloc "gl" plugin
# opens and closes every X display :0, :1, ... looking for NVIDIA GPUs. Closing the server's
# only client makes a default X server reset itself, and ParaView's own XOpenDisplay, a moment
# later, can land in that reset and fail ("bad X server connection"), more often under load.
# The server here never resets, and hwloc is told not to probe displays at all.
set -uo pipefail
export HWLOC_COMPONENTS=-gl,-opencl
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# A failed connection is still retried on a new server, in case of a cause not yet understood.
for attempt in 1 2 3; do
  fifo=$(mktemp -u)
  mkfifo "$fifo"
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp -noreset 3>"$fifo" 2>/dev/null &
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
