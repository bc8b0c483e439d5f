#!/usr/bin/env bash
# asrt trace --mpi under mpirun against a throwaway server (asrtWithThrowawayPostgres started it
# and set ASRT_TEST_CONNINFO): the distributed frame is the single-process frame bit for bit (the
# PNG, the VTI with every image array, and the stored records in order), for 2 and 4 processes
# and other splits; failures end every process with the right exit code, never a hang.
# Usage: mpi-trace.sh MPIEXEC ASRT STORECHECK EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
mpiexec="$1"; asrt="$2"; check="$3"; expect="$4"; scenes="$5"; work="$6"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
# The id of the one complete frame of a database. Not always 1: the ranks of a distributed write
# all insert the frame's row, and those that yield to the first have used up sequence values.
only_frame() {
  local frames; frames="$("$check" frames "$1")"
  [[ "$frames" =~ ^1\ complete:\ ([0-9]+)$ ]] || { echo "not one complete frame: $frames" >&2; return 1; }
  echo "${BASH_REMATCH[1]}"
}
# Bounded: mpirun ends its processes on SIGTERM; -k kills it if it does not.
mpi=(timeout -k 10 120 "$mpiexec" --oversubscribe -np)
scene="$scenes/kerr-disk.json"
size=61x47 # odd: rows do not divide evenly among the processes
# Every pixel traced (the default grid would deal rows in lattice blocks); the grid has its step.
every="--grid 1"

step "the single-process frame"
serial="$("$check" createdb serial)"
"$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace "$scene" -r $size $every -q --store --db "$serial" \
  -o serial

for n in 2 4; do
  step "$n processes: the same picture, image arrays and stored records"
  db="$("$check" createdb "np$n")"
  "$expect" 0 "$n processes, interleaved rows: steps max/mean" -- \
    "${mpi[@]}" "$n" "$asrt" trace "$scene" -r $size $every -q --mpi --store --db "$db" -o "np$n"
  cmp serial.png "np$n.png"
  cmp serial.vti "np$n.vti"
  "$check" same "$serial" "$db"
  test "$("$check" tiles "$db" "$(only_frame "$db")")" = "47/47"
done

step "3 processes, contiguous bands, and 2 with blocks of 5 rows: the same frame"
"$expect" 0 "3 processes, contiguous rows" -- \
  "${mpi[@]}" 3 "$asrt" trace "$scene" -r $size $every -q --mpi --mpi-split contiguous -o contiguous
cmp serial.png contiguous.png
cmp serial.vti contiguous.vti
db="$("$check" createdb blocks)"
"$expect" 0 "stored as frame [0-9]+" -- \
  "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size $every -q --mpi --mpi-split interleaved:5 --store --db "$db" \
  -o blocks
cmp serial.vti blocks.vti
"$check" same "$serial" "$db"
test "$("$check" tiles "$db" "$(only_frame "$db")")" = "10/10"

step "on the adaptive grid, 2 processes and 3 in contiguous bands: the single-process frame"
"$asrt" trace "$scene" -r $size -q --grid 8 --formats png,vti -o grid-serial
"${mpi[@]}" 2 "$asrt" trace "$scene" -r $size -q --mpi --grid 8 -o grid-np2
cmp grid-serial.png grid-np2.png
cmp grid-serial.vti grid-np2.vti
"${mpi[@]}" 3 "$asrt" trace "$scene" -r $size -q --mpi --mpi-split contiguous --grid 8 \
  -o grid-contiguous
cmp grid-serial.vti grid-contiguous.vti
if cmp -s serial.vti grid-serial.vti; then echo "the grid changed nothing" >&2; exit 1; fi

step "storing it again is refused by every process alike; --replace replaces it"
db2="${serial/dbname=serial/dbname=np2}"
"$expect" 3 "already stored.*--replace" -- \
  "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size $every -q --mpi --store --db "$db2" -o again
"$expect" 0 "stored as frame [0-9]+ \(one tile" -- \
  "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size $every -q --mpi --store --replace --db "$db2" -o again
"$check" same "$serial" "$db2"

step "an unreachable database and a bad scene end every process, with their exit codes"
"$expect" 3 "cannot connect" -- "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size $every -q --mpi --store \
  --db "host=/nonexistent port=1 connect_timeout=2" -o none
"$expect" 4 "exceeds the mass" -- "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size -q --mpi --spin 1.5 \
  -o none
test ! -e none.png
step "a failure of one process alone (process 0 cannot write the picture) ends the job"
"$expect" 1 "cannot" -- "${mpi[@]}" 2 "$asrt" trace "$scene" -r $size -q --mpi \
  -o /proc/asrt-out
echo "mpi-trace: all steps passed"
