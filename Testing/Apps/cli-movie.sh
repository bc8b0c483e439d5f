#!/usr/bin/env bash
# asrt movie against a throwaway server, which asrtWithThrowawayPostgres started and named in the
# PG* variables: a small mass ramp of Figs. 4-5 at --quality 35, every frame checked against the
# frame this script traces itself at that frame's parameters; the same movie again traces no ray
# and writes the same bytes (the movie file too); twice the frames on the same path reuses every
# old frame and traces fewer rays than its new frames would take traced directly, its new frames
# made through the pixels the old ones re-traced (and made again from the store, the same); a target the
# default rendering does not reach raises it (to 17 rays a pixel, or the accurate preset), one a
# cheaper cap reaches lowers it between the first and last frames; and the refusals, each with
# its exit code and nothing written.
# Usage: cli-movie.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
scene="$scenes/fig4-mass-start.json"
# Held to the frames traced at their parameters (--against-traced), the truth the steps below trace:
# at 48x48 the default rendering itself scores near 31 dB against the converged pictures.
movie=(--ramp mass=0.65:0.8 -n 7 -r 48x48 --quality 35 --against-traced -q)

step "--plan: the plan and its cost, nothing traced or written"
"$expect" 0 "plan: [0-9]+ key frames .* estimated [0-9]+ rays against [0-9]+ tracing every" -- \
  "$asrt" movie "$scene" "${movie[@]}" --plan --store -o plan/
"$check" '!plan/fig4-mass-start-000.png' '!plan/fig4-mass-start.pvd'
test "$("$asrt" list | tail -n +2 | wc -l)" -eq 0

step "the first run traces its key frames and the pixels the target needs, and stores them"
out="$("$expect" 0 "rays traced: [1-9][0-9]*$" -- "$asrt" movie "$scene" "${movie[@]}" --store=movie \
  -o first/)"
echo "$out"
grep -Eq "^ +[0-9]+ +[0-9.]+ +interpolated " <<< "$out" ||
  { echo "the movie interpolates no frame: what follows checks nothing of it" >&2; exit 1; }
grep -Eq "^ +3 +0\.725 +key " <<< "$out"
# The frames traced whole (keys, or traced because interpolating them costs more).
whole="$(awk '$1 ~ /^[0-9]+$/ && ($3 == "key" || $3 == "traced") { print $1 }' <<< "$out")"
"$check" first/fig4-mass-start-006.png=48x48 first/fig4-mass-start-003.vti=48x48 \
  first/fig4-mass-start.pvd=7 first/fig4-mass-start.ogv=7 '!first/fig4-mass-start-007.png'

step "every frame meets the target - 1 dB against the frame traced at its parameters"
"$asrt" trace "$scene" --sweep mass=0.65:0.8:7 -r 48x48 --formats png -q -o truth > /dev/null
for k in 0 1 2 3 4 5 6; do
  "$check" "first/fig4-mass-start-00$k.png:truth-00$k.png>=34"
done
step "key frames are the traced frames themselves"
for k in $whole; do cmp "first/fig4-mass-start-00$k.png" "truth-00$k.png"; done

step "the same movie again traces no ray, reuses every frame, and writes the same bytes"
out="$("$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${movie[@]}" --store -o second/)"
echo "$out"
grep -Eq "^ +3 +0\.725 +reused " <<< "$out"
if grep -Eq "^ +[0-9]+ +[0-9.]+ +(key|traced) " <<< "$out"; then echo "the second run traced a frame" >&2; exit 1; fi
for k in 0 1 2 3 4 5 6; do
  cmp "first/fig4-mass-start-00$k.png" "second/fig4-mass-start-00$k.png"
  cmp "first/fig4-mass-start-00$k.vti" "second/fig4-mass-start-00$k.vti"
done
cmp first/fig4-mass-start.ogv second/fig4-mass-start.ogv

step "--formats: only the outputs named, the same bytes as the whole set's"
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${movie[@]}" --store --formats png \
  -o pngs/ > /dev/null
for k in 0 1 2 3 4 5 6; do cmp "first/fig4-mass-start-00$k.png" "pngs/fig4-mass-start-00$k.png"; done
"$check" '!pngs/fig4-mass-start-000.vti' '!pngs/fig4-mass-start.pvd' '!pngs/fig4-mass-start.ogv'
"$expect" 0 "wrote vtis/fig4-mass-start-000.vti ... vtis/fig4-mass-start-006.vti, \
vtis/fig4-mass-start.pvd, vtis/m.ogv$" -- "$asrt" movie "$scene" "${movie[@]}" --store --formats vti,movie \
  --movie vtis/m.ogv -o vtis/ > /dev/null
for k in 0 1 2 3 4 5 6; do cmp "first/fig4-mass-start-00$k.vti" "vtis/fig4-mass-start-00$k.vti"; done
"$check" '!vtis/fig4-mass-start-000.png' vtis/fig4-mass-start.pvd=7 vtis/m.ogv=7
cmp first/fig4-mass-start.ogv vtis/m.ogv

step "each frame's pictures are stored with it; a key frame deleted, its frames are made again"
sql() { psql -XAtq -v ON_ERROR_STOP=1 "$@"; }
test "$(sql -c "SELECT count(*) FROM frame_pictures WHERE format = 'png.1'")" -eq 7
test "$(sql -c "SELECT count(*) FROM frame_pictures WHERE format = 'vti.1'")" -eq 7
key="$("$asrt" list | awk '$(NF - 5) == "48x48" && $(NF - 3) == 2304 && $0 ~ / 0\.725 / { print $1 }')"
test "$(wc -w <<< "$key")" -eq 1 || { echo "no one whole frame at M = 0.725: $key" >&2; exit 1; }
sql -c "DELETE FROM frames WHERE id = $key"
out="$("$expect" 0 "rays traced: [1-9][0-9]*$" -- "$asrt" movie "$scene" "${movie[@]}" --store \
  -o remade/)"
echo "$out"
# Its pictures went with it, and those of the frames made from it serve no more: made again.
for k in 0 1 2 3 4 5 6; do
  "$check" "remade/fig4-mass-start-00$k.png:truth-00$k.png>=34"
done
for k in 0 6; do cmp "first/fig4-mass-start-00$k.png" "remade/fig4-mass-start-00$k.png"; done

step "held to the converged pictures (the default): every frame meets the target - 1 dB there"
# A target the default rendering reaches at this size; the keys' own error against their converged
# pictures is measured by probe pixels traced converged, stored with the rest.
held=(--ramp mass=0.65:0.8 -n 7 -r 48x48 --quality 28 -q --store)
out="$("$expect" 0 "rays traced: [1-9][0-9]*$" -- "$asrt" movie "$scene" "${held[@]}" -o held/)"
echo "$out"
grep -Eq "^ +[0-9]+ +[0-9.]+ +interpolated " <<< "$out" ||
  { echo "the held movie interpolates no frame: what follows checks nothing of it" >&2; exit 1; }
"$asrt" trace "$scene" --sweep mass=0.65:0.8:7 -r 48x48 --antialias filter --supersample 4 \
  --grid 1 --formats png -q -o converged > /dev/null
for k in 0 1 2 3 4 5 6; do
  "$check" "held/fig4-mass-start-00$k.png:converged-00$k.png>=27"
done
step "the held movie again traces no ray, its probes read from the store, and writes the same bytes"
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${held[@]}" -o held-again/ > /dev/null
for k in 0 1 2 3 4 5 6; do
  cmp "held/fig4-mass-start-00$k.png" "held-again/fig4-mass-start-00$k.png"
done

step "a target neither the default rendering nor 17 rays a pixel reach: the accurate preset; a rendering asked for is kept"
# At 32x32 the default rendering reaches about 30 dB against the converged pictures, 17 rays a
# pixel about 38.
raise=(--ramp mass=0.65:0.8 -n 3 -r 32x32 --quality 40 -q)
"$expect" 0 "rendering: the accurate preset, since the default settings reach [0-9.]+ dB" -- \
  "$asrt" movie "$scene" "${raise[@]}" -o raised/ > /dev/null
"$asrt" trace "$scene" --sweep mass=0.65:0.8:3 -r 32x32 --preset accurate --formats png -q \
  -o accurate > /dev/null
"$asrt" trace "$scene" --sweep mass=0.65:0.8:3 -r 32x32 --formats png -q -o balanced > /dev/null
# The first and last frames are keys of every plan: the frames traced with the rendering chosen.
for k in 0 2; do cmp "raised/fig4-mass-start-00$k.png" "accurate-00$k.png"; done
out="$("$asrt" movie "$scene" "${raise[@]}" --preset balanced -o kept/)"
if grep -q "^rendering:" <<< "$out"; then echo "a rendering asked for was raised" >&2; exit 1; fi
for k in 0 2; do cmp "kept/fig4-mass-start-00$k.png" "balanced-00$k.png"; done

step "a target a cheaper cap reaches: the frames between the ends at 5 rays a pixel"
# At 32x32 the default rendering reaches about 30 dB against the converged pictures, 5 rays a pixel
# about 25 (its probes' bound).
low=(--ramp mass=0.65:0.8 -n 5 -r 32x32 --quality 20 -q --store)
out="$("$expect" 0 "rendering: at most 5 rays a pixel between the first and last frames" -- \
  "$asrt" movie "$scene" "${low[@]}" -o lowered/)"
echo "$out"
"$asrt" trace "$scene" --sweep mass=0.65:0.8:5 -r 32x32 --formats png -q -o low-default > /dev/null
"$asrt" trace "$scene" --sweep mass=0.65:0.8:5 -r 32x32 --max-rays 5 --formats png -q \
  -o low-cap5 > /dev/null
"$asrt" trace "$scene" --sweep mass=0.65:0.8:5 -r 32x32 --antialias filter --supersample 4 \
  --grid 1 --formats png -q -o low-converged > /dev/null
for k in 0 1 2 3 4; do
  "$check" "lowered/fig4-mass-start-00$k.png:low-converged-00$k.png>=19"
done
# The ends, traced at the default rendering to judge it, stay the movie's; the frames between
# traced whole are the cheaper cap's.
for k in 0 4; do cmp "lowered/fig4-mass-start-00$k.png" "low-default-00$k.png"; done
between="$(awk '$1 ~ /^[1-3]$/ && ($3 == "key" || $3 == "traced") { print $1 }' <<< "$out")"
test -n "$between" || { echo "no frame between the ends traced whole" >&2; exit 1; }
for k in $between; do cmp "lowered/fig4-mass-start-00$k.png" "low-cap5-00$k.png"; done
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${low[@]}" -o lowered-again/ > /dev/null
for k in 0 1 2 3 4; do
  cmp "lowered/fig4-mass-start-00$k.png" "lowered-again/fig4-mass-start-00$k.png"
done

step "a target the default misses and 17 rays a pixel reach: the movie at that cap"
high=(--ramp mass=0.65:0.8 -n 3 -r 32x32 --quality 30 -q --store)
"$expect" 0 "rendering: at most 17 rays a pixel, since the default settings reach" -- \
  "$asrt" movie "$scene" "${high[@]}" -o high/ > /dev/null
"$asrt" trace "$scene" --sweep mass=0.65:0.8:3 -r 32x32 --max-rays 17 --formats png -q \
  -o cap17 > /dev/null
# The ends anti-aliased again from the default's: the frames traced at that cap, bit for bit.
for k in 0 2; do cmp "high/fig4-mass-start-00$k.png" "cap17-00$k.png"; done
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${high[@]}" -o high-again/ > /dev/null
for k in 0 1 2; do cmp "high/fig4-mass-start-00$k.png" "high-again/fig4-mass-start-00$k.png"; done

step "twice the frames on the same path: the old frames reused whole, only the new ones traced"
dense=(--ramp mass=0.65:0.8 -n 13 -r 48x48 --quality 35 --against-traced -q --store)
out="$("$expect" 0 "rays traced: [1-9][0-9]*$" -- "$asrt" movie "$scene" "${dense[@]}" \
  --formats png -o double/)"
echo "$out"
# Frame k of the first movie is frame 2k of this one: read from the store, not traced again.
for k in 0 6 12; do grep -Eq "^ +$k +[0-9.]+ +reused " <<< "$out"; done
if awk '$1 ~ /^[0-9]+$/ && NF == 8 && $1 % 2 == 0 && $7 != 0 { found = 1 } END { exit !found }' \
  <<< "$out"; then echo "the denser movie traced rays for an old frame" >&2; exit 1; fi
for k in 0 1 2 3 4 5 6; do
  cmp "first/fig4-mass-start-00$k.png" "double/fig4-mass-start-$(printf %03d $((2 * k))).png"
done
traced="$(sed -n 's/^rays traced: \([0-9]*\)$/\1/p' <<< "$out")"
# The new frames traced directly, their rays counted from their frames' RaysPerPixel.
"$asrt" trace "$scene" --sweep mass=0.65:0.8:13 -r 48x48 --formats vti -q -o direct > /dev/null
direct=0
for k in 1 3 5 7 9 11; do
  rays="$("$check" "direct-$(printf %03d "$k").vti=48x48" | sed -n 's/.*, \([0-9]*\) rays$/\1/p')"
  direct=$((direct + rays))
done
echo "twice the frames: the second run traced $traced rays; its 6 new frames traced directly: $direct"
test "$traced" -lt "$direct" ||
  { echo "the denser movie traced more than its new frames would cost directly" >&2; exit 1; }

step "the new frames ran through the pixels the old ones re-traced, and still meet the target"
# Recorded by the chained recipe: made through the chains of the frames between their keys.
test "$(sql -c "SELECT count(*) FROM interpolated_frames WHERE recipe LIKE '%chained%'")" -gt 0
"$asrt" trace "$scene" --sweep mass=0.65:0.8:13 -r 48x48 --formats png -q -o dense-truth > /dev/null
for k in 1 3 5 7 9 11; do
  n="$(printf %03d "$k")"
  "$check" "double/fig4-mass-start-$n.png:dense-truth-$n.png>=34"
done

step "the denser movie made again (a format its pictures lack): no ray traced, the same bytes"
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${dense[@]}" --formats png,vti \
  -o double-again/ > /dev/null
for k in $(seq 0 12); do
  n="$(printf %03d "$k")"
  cmp "double/fig4-mass-start-$n.png" "double-again/fig4-mass-start-$n.png"
done

step "Ctrl-C a quarter into another movie: exit 130, the previous set intact, the keys kept"
snapshot() { (cd first && ls -A | LC_ALL=C sort && md5sum ./*); }
snapshot > before.txt
longer=(--ramp mass=0.3:0.6 -n 24 -r 48x48 --quality 35 --against-traced --store -o first/)
"$asrt" movie "$scene" "${longer[@]}" > run.txt 2> progress.txt &
pid=$!
quarter() { grep -Eq "movie of 24 frames: [0-9]+%" progress.txt; }
for _ in $(seq 1 1200); do quarter && break; sleep 0.05; done
quarter || { kill -KILL "$pid"; echo "no progress: $(cat progress.txt)" >&2; exit 1; }
kill -INT "$pid"
rc=0
wait "$pid" || rc=$?
cat progress.txt
test "$rc" -eq 130 || { echo "exit code $rc, expected 130" >&2; exit 1; }
grep -q "interrupted; nothing half-written was left" progress.txt
if grep -q "wrote" run.txt; then echo "success printed for an interrupted run" >&2; exit 1; fi
snapshot > after.txt
diff before.txt after.txt
test -z "$(find first -name '.*' -print)"
out="$("$expect" 0 "rays traced: [1-9]" -- "$asrt" movie "$scene" "${longer[@]}" -q -o longer/)"
grep -Eq "^ +[0-9]+ +[0-9.]+ +reused " <<< "$out" ||
  { echo "nothing stored before the interrupt was reused" >&2; exit 1; }

step "a shorter movie over a longer one: the longer one's frames beyond it go, others stay"
touch first/notes.txt first/fig4-mass-start-7.png
"$expect" 0 "rays traced: " -- "$asrt" movie "$scene" --ramp mass=0.65:0.8 -n 4 -r 48x48 -q \
  -o first/
"$check" first/fig4-mass-start-003.png=48x48 '!first/fig4-mass-start-004.png' \
  '!first/fig4-mass-start-006.vti' first/fig4-mass-start.pvd=4 first/fig4-mass-start.ogv=4
test -e first/notes.txt && test -e first/fig4-mass-start-7.png

step "a camera path through three key cameras: frame 0 is the first key as asrt trace sees it"
cat > cams.json <<'JSON'
{"keys": [
  {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]},
  {"position": [6, -29, 9], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]},
  {"position": [12, -27, 10], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]}]}
JSON
# The rendering asked for, as asrt trace uses it by default: at 48x48 the default rendering does
# not reach the default target, which would raise the movie's to the accurate preset.
"$expect" 0 "movie of 5 frames along the camera key" -- "$asrt" movie \
  "$scenes/fig1-cylinders.json" --cameras cams.json -n 5 -r 48x48 --preset balanced -q -o flight/
"$check" flight/fig1-cylinders-004.png=48x48 flight/fig1-cylinders.pvd=5 \
  flight/fig1-cylinders.ogv=5
"$asrt" trace "$scenes/fig1-cylinders.json" --camera 12,-27,10 -r 48x48 --formats png -q \
  -o flight-end > /dev/null
cmp flight/fig1-cylinders-004.png flight-end.png

step "PNGs alone on an empty store: each whole frame's PNG made as it is traced, stored with it"
small=(--ramp mass=0.65:0.8 -n 7 -r 40x40 --quality 35 --against-traced -q --formats png)
out="$("$expect" 0 "rays traced: [1-9][0-9]*$" -- "$asrt" movie "$scene" "${small[@]}" \
  --store=png-first -o png-first/)"
echo "$out"
"$asrt" trace "$scene" --sweep mass=0.65:0.8:7 -r 40x40 --formats png -q -o truth40 > /dev/null
whole="$(awk '$1 ~ /^[0-9]+$/ && ($3 == "key" || $3 == "traced") { print $1 }' <<< "$out")"
test -n "$whole"
for k in $whole; do cmp "png-first/fig4-mass-start-00$k.png" "truth40-00$k.png"; done
"$expect" 0 "rays traced: 0$" -- "$asrt" movie "$scene" "${small[@]}" --store -o png-again/ \
  > /dev/null
for k in 0 1 2 3 4 5 6; do
  cmp "png-first/fig4-mass-start-00$k.png" "png-again/fig4-mass-start-00$k.png"
done

step "refusals: exit codes, one clear line, nothing written"
"$expect" 1 "failed share is 100 % \(64 of 64 rays failed numerically.*--max-failed-share 1" -- \
  "$asrt" movie "$scene" --ramp mass=0.65:0.8 -n 3 -r 8x8 --method DormandPrince54 --step 1e300 \
  --store -o bad/
for q in 0 -3 nan 101 inf; do
  "$expect" 2 "^asrt movie: --quality: " -- "$asrt" movie "$scene" "${movie[@]}" --quality "$q" \
    -o bad/
done
"$expect" 2 "--ramp: unknown parameter 'temperature' \(mass, spin or charge\)" -- \
  "$asrt" movie "$scene" --ramp temperature=1:2 -n 3 -r 48x48 -o bad/
"$expect" 2 "give one path: --ramp P=FROM:TO, --orbit DEGREES or --cameras FILE.json" -- \
  "$asrt" movie "$scene" -n 3 -r 48x48 -o bad/
"$expect" 2 "--formats: unknown format 'vtp' \(png, vti, movie\)" -- \
  "$asrt" movie "$scene" "${movie[@]}" --formats png,vtp -o bad/
"$expect" 2 "--formats: the list is empty" -- "$asrt" movie "$scene" "${movie[@]}" --formats , -o bad/
"$expect" 2 "--movie: --formats leaves the movie file out" -- \
  "$asrt" movie "$scene" "${movie[@]}" --formats png --movie bad/m.ogv -o bad/
"$expect" 3 "^asrt movie: database: " -- "$asrt" movie "$scene" "${movie[@]}" --store \
  --db "host=$work/no-server-here port=1 connect_timeout=2" -o bad/
"$expect" 4 "frame 2 \(spin = 1\.5\)" -- "$asrt" movie "$scenes/kerr-disk.json" \
  --ramp spin=0.3:1.5 -n 3 -r 48x48 -o bad/
cat > one-key.json <<'JSON'
{"keys": [{"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1]}]}
JSON
"$expect" 4 "one-key.json: keys: a path needs at least 2 key cameras, got 1" -- \
  "$asrt" movie "$scenes/fig1-cylinders.json" --cameras one-key.json -n 3 -r 48x48 -o bad/
sed 's/\[6, -29, 9\]/[6, 1e999, 9]/' cams.json > overflow.json
"$expect" 4 "overflow.json: not valid JSON .*number overflow parsing '1e999'" -- \
  "$asrt" movie "$scenes/fig1-cylinders.json" --cameras overflow.json -n 3 -r 48x48 -o bad/
sed 's/\[6, -29, 9\]/[6, NaN, 9]/' cams.json > nan.json
"$expect" 4 "nan.json: not valid JSON" -- \
  "$asrt" movie "$scenes/fig1-cylinders.json" --cameras nan.json -n 3 -r 48x48 -o bad/
sed 's/\[6, -29, 9\]/[0.5, 0.5, 0.5]/' cams.json > inside.json
"$expect" 4 "frame 2 \(camera key = 1\): .*horizon" -- \
  "$asrt" movie "$scenes/fig1-cylinders.json" --cameras inside.json -n 5 -r 48x48 -o bad/
"$check" '!bad/fig4-mass-start-000.png' '!bad/fig4-mass-start.pvd' '!bad/fig4-mass-start.ogv' \
  '!bad/kerr-disk-000.png' '!bad/fig1-cylinders-000.png' '!bad/fig1-cylinders.ogv'
