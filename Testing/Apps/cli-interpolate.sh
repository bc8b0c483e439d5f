#!/usr/bin/env bash
# asrt interpolate against a throwaway server, which asrtWithThrowawayPostgres started and named in
# the PG* variables: two close frames of the mass ramp are stored, the frames between them are
# written and read back, and the pairs that cannot be interpolated are refused with their codes.
# Usage: cli-interpolate.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
# Stores with COMMAND and sets `stored` to the id it reports: ids come from the server's sequence,
# which may skip values, so they are read, never assumed.
store() {
  local out
  out="$("$expect" 0 "stored as frame [0-9]+" -- "$@")" || { echo "$out"; return 1; }
  echo "$out"
  stored="$("$here/stored-frame-id.sh" <<< "$out")"
}

step "store two ends of a short mass ramp (A, B), another size (SMALL), the Kerr disk (OTHER)"
store "$asrt" trace "$scenes/fig4-mass-start.json" -r 48x48 -q --mass 0.4 --store=ramp -o a
A="$stored"
store "$asrt" trace "$scenes/fig5-mass-end.json" -r 48x48 -q --mass 0.6 --store=ramp -o b
B="$stored"
store "$asrt" trace "$scenes/fig5-mass-end.json" -r 32x32 -q --mass 0.6 --store=small -o small
SMALL="$stored"
store "$asrt" trace "$scenes/kerr-disk.json" -r 48x48 -q --store=other -o other
OTHER="$stored"

step "interpolate 3 frames between them: PNG and VTI per frame, a .pvd series, an Ogg movie"
"$expect" 0 "matched%.*re-traced%" -- "$asrt" interpolate "$A" "$B" -n 3 -o movie/ -q
"$check" movie/interpolated-000.png=48x48 movie/interpolated-002.png=48x48 \
  movie/interpolated-004.png=48x48 movie/interpolated-004.vti=48x48 '!movie/interpolated-005.png' \
  movie/interpolated.pvd=5 movie/interpolated.ogv=5
step "the ends are the stored frames, shaded again: t = 0 is frame A as traced"
"$asrt" show "$A" --png a-stored.png > /dev/null
cmp movie/interpolated-000.png a-stored.png
"$asrt" show "$B" --png b-stored.png > /dev/null
cmp movie/interpolated-004.png b-stored.png
step "the mass at each frame runs linearly from 0.4 to 0.6"
"$asrt" interpolate "$A" "$B" -n 3 -o movie/ -q | grep -E "^ +2 +0\.5000 +0\.5 " > /dev/null

step "exact mode, a prefix and a movie named on the command line"
"$expect" 0 "exact mode" -- "$asrt" interpolate "$A" "$B" -n 1 --exact -o exact/ramp --movie exact-movie.ogv \
  --fps 5
"$check" exact/ramp-001.png=48x48 exact/ramp.pvd=3 exact-movie.ogv=3 '!exact/ramp.ogv'
if command -v ffmpeg > /dev/null; then
  step "MP4 through ffmpeg"
  "$expect" 0 "wrote mp4/m.mp4" -- "$asrt" interpolate "$A" "$B" -n 1 -o mp4/ --movie mp4/m.mp4 -q
  test -s mp4/m.mp4
fi

step "two scene files, traced first, nothing stored"
"$expect" 0 "scenes .*fig4-mass-start.json -> .*fig5-mass-end.json" -- "$asrt" interpolate \
  --scenes "$scenes/fig4-mass-start.json" "$scenes/fig5-mass-end.json" -r 24x24 -n 2 -o scenes/ -q
"$check" scenes/interpolated-003.png=24x24 scenes/interpolated.ogv=4
test "$("$asrt" list | tail -n +2 | wc -l)" -eq 4

step "a chain of key frames A (M = 0.4), MID (M = 0.5), B (M = 0.6): the sequence runs through each"
store "$asrt" trace "$scenes/fig4-mass-start.json" -r 48x48 -q --mass 0.5 --store=ramp -o mid
MID="$stored"
"$expect" 0 "frames $A -> $MID -> $B: 5 frames" -- "$asrt" interpolate "$A" "$MID" "$B" -n 1 -o chain/ -q
"$check" chain/interpolated-004.png=48x48 '!chain/interpolated-005.png' chain/interpolated.pvd=5 \
  chain/interpolated.ogv=5
"$asrt" show "$MID" --png mid-stored.png > /dev/null
cmp chain/interpolated-000.png a-stored.png
cmp chain/interpolated-002.png mid-stored.png
cmp chain/interpolated-004.png b-stored.png
"$asrt" interpolate "$A" "$MID" "$B" -n 1 -o chain/ -q > chain.txt
grep -E "^ +1 +0\.5000 +0\.45 " chain.txt > /dev/null
grep -E "^ +3 +1\.5000 +0\.55 " chain.txt > /dev/null

step "errors: usage (2), the database (3), a pair that cannot be interpolated (4); nothing written"
"$expect" 2 "two frame ids" -- "$asrt" interpolate "$A"
"$expect" 2 "not a frame id" -- "$asrt" interpolate "$A" two
"$expect" 2 "--frames" -- "$asrt" interpolate "$A" "$B" -n 0
"$expect" 2 "--movie" -- "$asrt" interpolate "$A" "$B" --movie x.avi
"$expect" 3 "no stored frame 999999999999" -- "$asrt" interpolate "$A" 999999999999 -o bad/
"$expect" 3 "cannot connect" -- "$asrt" interpolate "$A" "$B" -o bad/ \
  --db "host=/nonexistent port=1 connect_timeout=2"
"$expect" 4 "different resolutions" -- "$asrt" interpolate "$A" "$SMALL" -o bad/
"$expect" 4 "different scenes" -- "$asrt" interpolate "$A" "$OTHER" -o bad/
"$expect" 4 "different resolutions" -- "$asrt" interpolate "$A" "$B" "$SMALL" -o bad/
"$expect" 2 "--resolution only" -- "$asrt" interpolate "$A" "$B" -r 8x8 -o bad/
"$expect" 2 "--against-traced goes with --quality" -- "$asrt" interpolate "$A" "$B" \
  --against-traced -o bad/
"$expect" 4 "cannot read scene file" -- "$asrt" interpolate --scenes no-such.json \
  "$scenes/fig5-mass-end.json" -r 8x8 -o bad/
"$check" '!bad/interpolated-000.png' '!bad/interpolated.ogv' '!bad/interpolated.pvd'
echo "cli-interpolate: all steps passed"
