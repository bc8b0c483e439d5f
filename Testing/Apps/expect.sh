#!/usr/bin/env bash
# Runs a command and checks its exit code and, optionally, that its output (stdout and stderr)
# matches an extended regular expression.
# Usage: expect.sh CODE [PATTERN] -- COMMAND [ARGS...]
set -u
code="$1"; shift
pattern=""
if [ "$1" != "--" ]; then pattern="$1"; shift; fi
shift # --
output="$("$@" 2>&1)"
rc=$?
printf '%s\n' "$output"
if [ "$rc" -ne "$code" ]; then
  echo "expect.sh: exit code $rc, expected $code: $*" >&2
  exit 1
fi
if [ -n "$pattern" ] && ! printf '%s\n' "$output" | grep -Eq -- "$pattern"; then
  echo "expect.sh: output does not match /$pattern/: $*" >&2
  exit 1
fi
if printf '%s\n' "$output" | grep -Eq 'ERROR: In |vtkErrorMacro|Aborted|terminate called'; then
  echo "expect.sh: VTK's raw error output or a crash leaked through: $*" >&2
  exit 1
fi
exit 0
