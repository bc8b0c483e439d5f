#!/usr/bin/env bash
# Runs a command with an X server of its own (Xvfb, 24-bit, 1280x1024). Xvfb chooses a free
# display number itself (-displayfd), so concurrent runs never take the same one.
#
# ParaView's render windows abort with "bad X server connection" when XOpenDisplay fails. On a
# loaded machine that happened to about 1 run in 6 of the pvpython example, on its first view,
# with its own live server (cause not found; the same was seen on ParaView's own saves). Such a run
# says nothing of ASRT, so it is run once more on a new server, and the retry is said on stderr;
# any other failure, or a second one, is the command's.
# Usage: with-own-display.sh COMMAND [ARGS...]
set -uo pipefail
run_on_new_display() {
  local fifo server number rc
  fifo=$(mktemp -u /tmp/asrt-display-XXXXXX)
  mkfifo "$fifo"
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3> "$fifo" > /dev/null 2>&1 &
  server=$!
  # Xvfb writes the display number once it accepts connections; bounded in case it cannot start.
  if ! read -r -t 60 number < "$fifo"; then
    echo "with-own-display: Xvfb did not start" >&2
    kill "$server" 2> /dev/null; rm -f "$fifo"
    return 1
  fi
  rm -f "$fifo"
  DISPLAY=":$number" XAUTHORITY= "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  kill "$server" 2> /dev/null; wait "$server" 2> /dev/null
  return "$rc"
}
log=$(mktemp /tmp/asrt-display-log-XXXXXX)
trap 'rm -f "$log"' EXIT
run_on_new_display "$@" && exit 0
rc=$?
if grep -q "bad X server connection" "$log"; then
  echo "with-own-display: the X connection failed (not the command's doing); once more on a new server" >&2
  run_on_new_display "$@"
  exit $?
fi
exit "$rc"
