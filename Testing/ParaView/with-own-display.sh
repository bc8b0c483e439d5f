#!/usr/bin/env bash
# Runs a command with an X server of its own (Xvfb, 24-bit, 1280x1024). Xvfb chooses a free
# display number itself (-displayfd), so concurrent runs never take the same one.
#
# -noreset: by default an X server resets when its last client disconnects, and a connection
# opened during the reset fails ("unable to open display"; VTK's "bad X server connection", which
# aborts). ParaView opens and closes a display to probe OpenGL before its first view, so without it
# the view's own connection could fall into the reset: about 1 pvpython run in 6 on a loaded
# machine, and about 1 xdpyinfo in 17 run back to back (none of 400 with -noreset).
# Usage: with-own-display.sh COMMAND [ARGS...]
set -uo pipefail
fifo=$(mktemp -u /tmp/asrt-display-XXXXXX)
mkfifo "$fifo"
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp -noreset 3> "$fifo" > /dev/null 2>&1 &
server=$!
# Xvfb writes the display number once it accepts connections; bounded in case it cannot start.
if ! read -r -t 60 number < "$fifo"; then
  echo "with-own-display: Xvfb did not start" >&2
  kill "$server" 2> /dev/null; rm -f "$fifo"
  exit 1
fi
rm -f "$fifo"
DISPLAY=":$number" XAUTHORITY= "$@"
rc=$?
kill "$server" 2> /dev/null; wait "$server" 2> /dev/null
exit "$rc"
