#!/usr/bin/env bash
# Runs a command and checks its exit code and that its stderr is one plain line matching an
# extended regular expression: no ANSI escape sequences, no second line (a VTK warning beside the
# error, a progress bar).
# Usage: expect-one-line-error.sh CODE PATTERN -- COMMAND [ARGS...]
set -u
code="$1"; pattern="$2"; shift 3 # CODE PATTERN --
err="$("$@" 2>&1 >/dev/null)"
rc=$?
printf '%s\n' "$err"
if [ "$rc" -ne "$code" ]; then
  echo "expect-one-line-error.sh: exit code $rc, expected $code: $*" >&2
  exit 1
fi
if printf '%s' "$err" | grep -q $'\x1b'; then
  echo "expect-one-line-error.sh: an ANSI escape sequence reached stderr: $*" >&2
  exit 1
fi
lines="$(printf '%s\n' "$err" | wc -l)"
if [ "$lines" -ne 1 ] || [ -z "$err" ]; then
  echo "expect-one-line-error.sh: stderr has $lines lines, expected one: $*" >&2
  exit 1
fi
if ! printf '%s\n' "$err" | grep -Eq -- "$pattern"; then
  echo "expect-one-line-error.sh: stderr does not match /$pattern/: $*" >&2
  exit 1
fi
exit 0
