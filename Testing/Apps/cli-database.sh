#!/usr/bin/env bash
# asrt's database subcommands against a throwaway server, which asrtWithThrowawayPostgres started
# and named in the PG* variables (no --db: the standard variables must be honoured).
# Usage: cli-database.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
# Stores with COMMAND (which must say "stored as frame N") and sets `stored` to the last N: ids
# come from the server's sequence, which may skip values, so they are read, never assumed.
store() {
  local out
  out="$("$expect" 0 "stored as frame [0-9]+" -- "$@")" || { echo "$out"; return 1; }
  echo "$out"
  stored="$("$here/stored-frame-id.sh" <<< "$out")"
}

step "a database the user names gets no schema from a reading command; asrt db init makes it"
"$expect" 3 "holds no ASRT schema.*asrt db init" -- "$asrt" list
"$expect" 0 "schema version [0-9]+ created" -- "$asrt" db init
step "an empty store lists nothing"
"$expect" 0 "no frames stored yet" -- "$asrt" list

step "trace and store; the same frame again is refused, with --replace it is replaced"
store "$asrt" trace "$scenes/fig4-mass-start.json" -r 24x24 -q --store=start -o start
first="$stored"
"$expect" 3 "already stored.*--replace" -- "$asrt" trace "$scenes/fig4-mass-start.json" -r 24x24 \
  -q --store=start -o start
store "$asrt" trace "$scenes/fig4-mass-start.json" -r 24x24 -q --store=start --replace -o start
test "$stored" != "$first" # a replaced frame is a new row
"$check" start.png=24x24

step "a sweep stores every frame; list shows them with their parameters and labels"
store "$asrt" trace "$scenes/fig4-mass-start.json" -r 32x32 -q --sweep mass=0.1:1.2:2 \
  --store="mass ramp" -o ramp
ramp_end="$stored"
"$expect" 0 "mass ramp" -- "$asrt" list
"$asrt" list | grep -E "^ +$ramp_end .*mass ramp +1\.2 " > /dev/null

step "a hostile label is stored as given and shown escaped"
store "$asrt" trace "$scenes/fig2-no-hole.json" -r 8x8 -q --store=$'evil\e[2J\nlabel' -o evil
"$asrt" show "$stored" | grep -F 'evil\x1b[2J\x0alabel' > /dev/null
if "$asrt" list | grep -q $'\e'; then echo "raw escape character in the listing"; exit 1; fi

step "show prints the parameters and exports the frame through the reader"
"$expect" 0 "mass +1.2" -- "$asrt" show "$ramp_end" --png f4.png --vti f4.vti --vtp f4.vtp
"$check" f4.png=32x32 f4.vti=32x32 f4.vtp=1024
step "the exported picture is the traced one, pixel for pixel"
cmp f4.png ramp-001.png
step "an SQL selection of rays"
"$expect" 0 "wrote rings.png" -- "$asrt" show "$ramp_end" --where "image_order >= 1" --png rings.png
"$check" "~rings.png=32x32"
"$expect" 3 "predicate" -- "$asrt" show "$ramp_end" --where "drop table frames" --png x.png
"$check" '!x.png'

step "errors: no such frame, not an id, unreachable server"
"$expect" 3 "no frame 999999999999" -- "$asrt" show 999999999999
"$expect" 2 "not a frame id" -- "$asrt" show abc
"$expect" 3 "cannot connect" -- "$asrt" list --db "host=/nonexistent port=1 connect_timeout=2"
ASRT_DB="host=/nonexistent port=1 connect_timeout=2" "$expect" 3 "cannot connect" -- "$asrt" list
step "the store still holds every frame"
test "$("$asrt" list | tail -n +2 | wc -l)" -eq 4
echo "cli-database: all steps passed"
