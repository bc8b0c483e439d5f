#!/usr/bin/env bash
# Runs a command with an X server of its own (Xvfb, 24-bit, 1280x1024): ParaView's clients abort
# on "bad X server connection" when the display they were given is gone or refuses them, and a
# display shared by the whole suite is only as good as the other tests leave it. Xvfb chooses a
# free display number itself (-displayfd), so concurrent runs never take the same one.
# Usage: with-own-display.sh COMMAND [ARGS...]
set -euo pipefail
fifo=$(mktemp -u /tmp/asrt-display-XXXXXX)
mkfifo "$fifo"
Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3> "$fifo" > /dev/null 2>&1 &
server=$!
trap 'kill "$server" 2> /dev/null || true; wait "$server" 2> /dev/null || true; rm -f "$fifo"' EXIT
# Xvfb writes the display number once it accepts connections; bounded in case it cannot start.
read -r -t 60 number < "$fifo" || { echo "with-own-display: Xvfb did not start" >&2; exit 1; }
export DISPLAY=":$number"
unset XAUTHORITY
"$@"
