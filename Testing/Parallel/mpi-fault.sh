#!/usr/bin/env bash
# A process dies in the middle of a distributed, stored frame (asrtDistributedFault: process 1
# raises SIGKILL on itself after committing 3 of its tiles). mpirun must end the job promptly,
# and the database must show no part of the frame: listFrames and SQL see nothing,
# abandonedFrames finds it, and after deleteFrame a rerun stores the whole frame, equal to the
# single-process one.
# Usage: mpi-fault.sh MPIEXEC ASRT FAULT_PROGRAM STORECHECK EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
mpiexec="$1"; asrt="$2"; fault="$3"; check="$4"; expect="$5"; scenes="$6"; work="$7"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
mpi=(timeout -k 10 120 "$mpiexec" --oversubscribe -np)
# The Kerr disk with every pixel traced: a tile a row (the default grid deals rows in blocks of
# its lattice), its texture beside it as the scene's relative path expects.
mkdir -p scenes textures
cp "$scenes/../textures/galaxy.png" textures/
sed '0,/{/s//{ "rendering": { "gridLattice": 1 },/' "$scenes/kerr-disk.json" > scenes/kerr-disk.json
scene="$work/scenes/kerr-disk.json"
db="$("$check" createdb fault)"

step "process 1 dies after 3 of its 24 tiles"
start=$SECONDS
rc=0
"${mpi[@]}" 2 "$fault" "$scene" 64 48 "$db" 1 3 || rc=$?
elapsed=$((SECONDS - start))
echo "mpirun exited with $rc after ${elapsed} s"
test "$rc" -ne 0
test "$elapsed" -lt 100 # mpirun ended the job itself, well before the timeout

step "nothing of the frame is visible"
test "$("$check" frames "$db")" = "0 complete:"
"$expect" 0 "no frames stored yet" -- "$asrt" list --db "$db"
read -r -a abandoned <<< "$("$check" abandoned "$db")"
test "${#abandoned[@]}" -eq 1
id="${abandoned[0]}"
tiles="$("$check" tiles "$db" "$id")"
echo "frame $id: $tiles tiles committed"
written="${tiles%/*}"
test "${tiles#*/}" -eq 48
test "$written" -ge 3
test "$written" -lt 48
test "$("$check" visible-rays "$db" "$id")" -eq 0

step "a rerun joins the abandoned frame, finds its tiles written, and leaves it to be deleted"
"$expect" 3 "already written.*abandonedFrames" -- \
  "${mpi[@]}" 2 "$asrt" trace "$scene" -r 64x48 -q --mpi --store --db "$db" -o joined
test "$("$check" tiles "$db" "$id")" = "$tiles"
test "$("$check" frames "$db")" = "0 complete:"

step "deleted, the frame is traced and stored again, whole and equal to the single-process one"
"$check" delete "$db" "$id"
test -z "$("$check" abandoned "$db" | tr -d ' ')"
"$expect" 0 "stored as frame" -- \
  "${mpi[@]}" 2 "$asrt" trace "$scene" -r 64x48 -q --mpi --store --db "$db" -o rerun
read -r count _ <<< "$("$check" frames "$db")"
test "$count" -eq 1
serial="$("$check" createdb serial)"
"$asrt" trace "$scene" -r 64x48 -q --store --db "$serial" -o serial > /dev/null
"$check" same "$serial" "$db"
cmp serial.png rerun.png
echo "mpi-fault: all steps passed"
