#!/usr/bin/env bash
# asrt interpolate writes a sequence as one set of files, against a throwaway server that
# asrtWithThrowawayPostgres started and named in the PG* variables. Over a previous, longer
# sequence: a shorter run leaves exactly its own frames (the older ones beyond it removed, other
# files kept); a run that fails (exact mode without the scene's texture) or is interrupted
# (Ctrl-C mid-sequence) leaves the previous sequence byte for byte, with no temporary, and says
# why in one line; a movie named as a FIFO is written through it.
# Usage: cli-interpolate-sets.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"
one_line="$(dirname "$expect")/expect-one-line-error.sh"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
fail() { echo "FAILED: $*" >&2; exit 1; }
wait_until() {
  for _ in $(seq 1 1200); do
    if "$@"; then return 0; fi
    sleep 0.05
  done
  return 1
}
stopped() { ! kill -0 "$1" 2> /dev/null; }
# The names in the folder, hidden ones included, and every regular file's checksum.
snapshot() {
  (cd "$1" && ls -A | LC_ALL=C sort &&
    find . -type f -print0 | LC_ALL=C sort -z | xargs -0 -r md5sum)
}
unchanged() {
  snapshot seq > after.txt
  diff before.txt after.txt > /dev/null ||
    fail "the previous sequence changed: $(diff before.txt after.txt | head)"
}

step "the scenes and their textures copied here, two frames of the mass ramp stored from them"
cp -r "$scenes" scenes
cp -r "$scenes/../textures" textures
# The ids are read from what the store reports: a sequence may skip values.
stored_id() { "$here/stored-frame-id.sh"; }
A="$("$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace scenes/fig4-mass-start.json -r 48x48 -q \
  --mass 0.4 --store=ramp -o a | stored_id)"
B="$("$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace scenes/fig5-mass-end.json -r 48x48 -q \
  --mass 0.6 --store=ramp -o b | stored_id)"
test -n "$A" && test -n "$B" || fail "the stored frames' ids were not reported"

# The previous sequence runs backwards (2 -> 1): every frame of it differs from a run 1 -> 2.
previous_sequence() {
  "$asrt" interpolate 2 1 -n 30 -o seq/ -q > /dev/null
  snapshot seq > before.txt
}

step "a shorter sequence over a longer one: exactly its own frames remain, other files are kept"
previous_sequence
others=(interpolated-notes.png interpolated-0031.png other-031.png interpolated-031-hits.vtp)
for other in "${others[@]}"; do
  echo "not a frame" > "seq/$other"
done
"$expect" 0 "removed 54 files of an earlier, longer sequence" -- \
  "$asrt" interpolate "$A" "$B" -n 3 -o seq/ -q
"$check" seq/interpolated-000.png=48x48 seq/interpolated-004.png=48x48 \
  seq/interpolated-004.vti=48x48 seq/interpolated.pvd=5 seq/interpolated.ogv=5
for k in 005 017 031; do
  for ext in png vti; do
    test ! -e "seq/interpolated-$k.$ext" || fail "seq/interpolated-$k.$ext of the older run is left"
  done
done
test "$(ls -A seq | wc -l)" -eq $((5 * 2 + 2 + 4)) || fail "unexpected files: $(ls -A seq)"
for other in "${others[@]}"; do
  test "$(cat "seq/$other")" = "not a frame" || fail "seq/$other was touched"
done
"$asrt" show "$A" --png a-stored.png > /dev/null
cmp seq/interpolated-000.png a-stored.png || fail "frame 000 is not frame A"

step "exact mode without the scene's texture: exit 4 in one line, the previous sequence intact"
rm -r seq
previous_sequence
mv textures/galaxy.png galaxy.png.aside
"$one_line" 4 "exact mode cannot load the frames' scene.*galaxy\.png" -- \
  "$asrt" interpolate "$A" "$B" -n 3 --exact --textures scenes -o seq/ -q
mv galaxy.png.aside textures/galaxy.png
unchanged

step "Ctrl-C a quarter into a long sequence: exit 130, the previous sequence intact"
# Progress lines (stderr is no terminal) show that frames were being written when the signal
# came: three quarters of 2002 frames are left to do then.
"$asrt" interpolate "$A" "$B" -n 2000 -o seq/ > run.txt 2> progress.txt &
pid=$!
quarter_done() { grep -q "interpolate $A -> $B: 25%" progress.txt; }
wait_until quarter_done || { kill -KILL "$pid"; fail "no progress: $(cat progress.txt)"; }
kill -INT "$pid"
wait_until stopped "$pid" || { kill -KILL "$pid"; fail "asrt did not stop on Ctrl-C"; }
rc=0
wait "$pid" || rc=$?
cat progress.txt
test "$rc" -eq 130 || fail "exit code $rc, expected 130"
grep -q "interrupted" progress.txt || fail "no word of the interrupt"
grep -q "wrote" run.txt && fail "success printed for an interrupted run"
unchanged

step "a movie named as a FIFO is written through it, and the FIFO stays"
mkfifo movie.ogv
cat movie.ogv > captured.ogv &
reader=$!
"$expect" 0 "wrote movie.ogv" -- "$asrt" interpolate "$A" "$B" -n 3 -o through/ --movie movie.ogv -q
test -p movie.ogv || { kill "$reader"; fail "the FIFO was replaced"; }
wait_until stopped "$reader" || { kill "$reader"; fail "the FIFO's reader got no end of file"; }
"$check" captured.ogv=5 through/interpolated.pvd=5 '!through/interpolated.ogv'
echo "cli-interpolate-sets: all steps passed"
