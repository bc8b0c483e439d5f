#!/usr/bin/env bash
# Runs a command in a fresh directory, then checks the files it wrote.
# Usage: run-and-check.sh DIR CHECKER [SPEC...] -- COMMAND [ARGS...]
#   DIR is emptied and becomes the working directory; the SPECs (see CheckOutputs.cxx) are
#   relative to it. The command must succeed.
set -euo pipefail
dir="$1"; checker="$2"; shift 2
specs=()
while [ "$1" != "--" ]; do specs+=("$1"); shift; done
shift
rm -rf "$dir"
mkdir -p "$dir"
cd "$dir"
"$@"
"$checker" "${specs[@]}"
