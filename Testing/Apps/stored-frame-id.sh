#!/usr/bin/env bash
# Prints the id of the last frame that the output on stdin reports stored ("stored as frame N").
# Ids come from the server's sequence, which may skip values: tests read them, never assume them.
# Fails when no id was reported.
set -euo pipefail
id="$(sed -n 's/.*stored as frame \([0-9][0-9]*\).*/\1/p' | tail -n 1)"
[ -n "$id" ] || { echo "stored-frame-id: no stored frame reported" >&2; exit 1; }
echo "$id"
