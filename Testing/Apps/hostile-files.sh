#!/usr/bin/env bash
# Output files and interrupts under hostile conditions: links planted in the output folder, a
# file-size limit, a read-only folder, a directory where a file of the set goes, stale
# temporaries, a scene that is a FIFO, outputs that are FIFOs, devices, sockets and links to
# devices, and Ctrl-C while a frame is being stored (the cases that need a database run under
# asrtWithThrowawayPostgres). Every case checks that the previous run's files are untouched and
# that no new file or temporary (".NAME.PID.XXXXXX.part") remains. The only system files used are
# /dev/null and /dev/full, written through, and checked to be character devices afterwards.
# Usage: hostile-files.sh CASE ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
case_name="$1"; asrt="$2"; check="$3"; expect="$4"; scenes="$5"; work="$6/$1"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
scene="$scenes/fig2-no-hole.json"
name=fig2-no-hole
step() { echo "== $*"; }
fail() { echo "FAILED: $*" >&2; exit 1; }

# Polls until "$@" succeeds; a bounded wait for a state the test brings about, never a timing.
wait_until() {
  for _ in $(seq 1 600); do
    if "$@"; then return 0; fi
    sleep 0.05
  done
  return 1
}
running() { kill -0 "$1" 2> /dev/null; }
stopped() { ! running "$1"; }

# The checksums and the names of the folder's files, hidden ones included.
snapshot() {
  (cd "$1" && ls -A | LC_ALL=C sort && find . -type f -print0 | LC_ALL=C sort -z | xargs -0 -r md5sum)
}
previous_run() {
  "$asrt" trace "$scene" -r 16x16 -q -o out/
  snapshot out > before.txt
}
unchanged() {
  snapshot out > after.txt
  diff before.txt after.txt || fail "the previous run's files changed, or a file was left"
}

planted_links() {
  step "links planted at the temporary names the program used to write to, and at the final names"
  echo precious > victim
  mkdir out
  # A subshell that becomes asrt (exec keeps the process id): its temporaries' old names are known.
  (
    for file in $name.png $name.vti $name-hits.vtp; do
      ln -s "$work/victim" "out/.$file.$BASHPID.part"
      ln -s "$work/victim-$file" "out/$file"
      echo "precious $file" > "victim-$file"
    done
    exec "$asrt" trace "$scene" -r 16x16 -q -o out/
  )
  test "$(cat victim)" = precious || fail "written through a link at a temporary name"
  for file in $name.png $name.vti $name-hits.vtp; do
    test "$(cat "victim-$file")" = "precious $file" || fail "written through the link out/$file"
    test ! -L "out/$file" || fail "out/$file is still a link"
  done
  "$check" "out/$name.png=16x16" "out/$name.vti=16x16" "out/$name-hits.vtp=256"
  test "$(ls -A out | grep -c '\.part$')" -eq 3 || fail "a temporary was left (or a planted link removed)"
}

file_size_limit() {
  step "over the file-size limit (as a full disk): exit 1, the previous files untouched"
  previous_run
  # 8 kB: the new picture and image data fit, the hits do not. Without SIGXFSZ ignored, the limit kills.
  (
    ulimit -f 8
    "$expect" 1 "cannot write \"out/$name-hits.vtp\": File too large" -- \
      "$asrt" trace "$scene" -r 16x16 -q --mass 0.5 -o out/
  )
  unchanged
}

read_only_folder() {
  step "a read-only output folder: exit 1 naming the file and the reason, nothing changed"
  # Root writes into read-only folders: the run then drops to an ordinary user.
  as_user=()
  if [ "$(id -u)" -eq 0 ]; then
    as_user=(setpriv --reuid=nobody --regid=nogroup --clear-groups --)
    chmod a+rwx "$work"
    # nobody needs to reach the program, the scene and this folder: say so, rather than fail on
    # an unrelated "Permission denied".
    for needed in "$asrt" "$scene" "$work"; do
      "${as_user[@]}" test -r "$needed" || fail "user nobody cannot reach $needed: the build and \
source folders and their parents must be enterable by other users (chmod o+x)"
    done
  fi
  "${as_user[@]}" "$asrt" trace "$scene" -r 16x16 -q -o out/
  snapshot out > before.txt
  chmod a-w out
  "${as_user[@]}" "$expect" 1 "cannot write \"out/$name.png\": Permission denied" -- \
    "$asrt" trace "$scene" -r 16x16 -q --mass 0.5 -o out/
  chmod u+w out
  unchanged
}

directory_in_the_set() {
  step "a directory where one file of the set goes: refused before any file of the set changes"
  previous_run
  rm out/$name-hits.vtp
  mkdir -p out/$name-hits.vtp/inside
  snapshot out > before.txt
  "$expect" 1 "cannot write \"out/$name-hits.vtp\": Is a directory" -- \
    "$asrt" trace "$scene" -r 16x16 -q --mass 0.5 -o out/
  unchanged
}

stale_temporaries() {
  step "temporaries left by a dead asrt are removed; a living one's and others' files are kept"
  mkdir out
  bash -c 'exit 0' &
  dead=$!
  wait "$dead"
  touch "out/.$name.png.$dead.AbC123.part" "out/.$name.png.1.AbC123.part" out/.notes.part
  "$expect" 0 "wrote out/$name.png" -- "$asrt" trace "$scene" -r 8x8 -q -o out/
  test ! -e "out/.$name.png.$dead.AbC123.part" || fail "the dead writer's temporary is still there"
  test -e "out/.$name.png.1.AbC123.part" || fail "a living process's temporary was removed"
  test -e out/.notes.part || fail "a file that is not a temporary of asrt was removed"
}

# Sends SIGTERM to asrt once it holds `what` open, and expects exit code 130 (it must not stay
# blocked).
expect_130_on_sigterm() {
  local what="$1"; shift
  "$asrt" "$@" > out.txt 2>&1 3>&- &
  local pid=$!
  wait_until bash -c "ls -l /proc/$pid/fd 2> /dev/null | grep -qF -- '$what'" ||
    fail "asrt never opened $what"
  kill -TERM "$pid"
  if ! wait_until stopped "$pid"; then
    kill -KILL "$pid"
    fail "asrt did not stop on SIGTERM while reading $what"
  fi
  local rc=0
  wait "$pid" || rc=$?
  cat out.txt
  test "$rc" -eq 130 || fail "exit code $rc, expected 130"
  grep -q interrupted out.txt || fail "no word of the interrupt"
}

scene_fifo() {
  step "SIGTERM while the scene is read from a FIFO nobody writes to: exit 130"
  mkfifo scene.json
  # A writer holds the FIFO open and writes nothing: asrt's open returns, its read blocks.
  exec 3<> scene.json
  expect_130_on_sigterm scene.json trace scene.json -r 8x8 -q -o out/
  exec 3>&-
  test ! -e out || test -z "$(ls -A out)" || fail "files were written"

  step "SIGTERM while opening a FIFO that no one has opened for writing: exit 130"
  "$asrt" trace scene.json -r 8x8 -q -o out/ > out.txt 2>&1 &
  pid=$!
  # The handler is in place (SIGTERM caught) and the process waits in openat (syscall 257).
  opening() {
    local caught syscall
    caught=$(sed -n 's/^SigCgt:[[:space:]]*//p' "/proc/$pid/status" 2> /dev/null) || return 1
    syscall=$(cut -d' ' -f1 "/proc/$pid/syscall" 2> /dev/null) || return 1
    test -n "$caught" && test $((0x$caught & 0x4000)) -ne 0 && test "$syscall" = 257
  }
  wait_until opening || fail "asrt never waited to open the FIFO"
  kill -TERM "$pid"
  if ! wait_until stopped "$pid"; then
    kill -KILL "$pid"
    fail "asrt did not stop on SIGTERM while opening the FIFO"
  fi
  rc=0
  wait "$pid" || rc=$?
  cat out.txt
  test "$rc" -eq 130 || fail "exit code $rc, expected 130"

  step "an endless scene file is cut at the limit"
  "$expect" 4 "larger than 64 MiB" -- "$asrt" trace /dev/zero -r 8x8 -q -o out/
}

fifo_outputs() {
  step "a FIFO named as an output is written through, and stays a FIFO"
  "$asrt" trace "$scene" -r 64x64 -q --formats png -o ref/
  mkdir out
  mkfifo out/$name.png
  cat out/$name.png > captured &
  reader=$!
  "$expect" 0 "wrote out/$name.png" -- "$asrt" trace "$scene" -r 64x64 -q --formats png,vti -o out/
  test -p out/$name.png || { kill "$reader"; fail "the FIFO was replaced"; }
  wait_until stopped "$reader" || { kill "$reader"; fail "the FIFO's reader got no end of file"; }
  cmp captured ref/$name.png || fail "the FIFO's reader did not get the picture"
  "$check" out/$name.vti=64x64

  step "a FIFO that no process reads is refused at once; nothing of the set is written"
  snapshot out > before.txt
  "$expect" 1 "cannot write \"out/$name.png\": it is a FIFO that no process is reading" -- \
    "$asrt" trace "$scene" -r 64x64 -q --formats png,vti --mass 0.5 -o out/
  test -p out/$name.png || fail "the FIFO was replaced"
  unchanged

  step "Ctrl-C while a FIFO's reader reads nothing: exit 130, no file of the set renamed"
  # This shell holds the FIFO open to read, and never reads: the picture (larger than a pipe
  # holds) waits to be written.
  exec 3<> out/$name.png
  "$asrt" trace "$scene" -r 400x400 -q --formats png,vti --mass 0.5 -o out/ > out.txt 2>&1 &
  pid=$!
  # asrt waits to write to the FIFO: in ppoll (syscall 271), its picture's descriptor open.
  writing_to_fifo() {
    local syscall
    syscall=$(cut -d' ' -f1 "/proc/$pid/syscall" 2> /dev/null) || return 1
    test "$syscall" = 271 && ls -l "/proc/$pid/fd" 2> /dev/null | grep -qF "out/$name.png"
  }
  wait_until writing_to_fifo || { kill -KILL "$pid"; fail "asrt never waited to write the FIFO"; }
  kill -INT "$pid"
  if ! wait_until stopped "$pid"; then
    kill -KILL "$pid"
    fail "asrt did not stop on Ctrl-C while writing to the FIFO"
  fi
  exec 3>&-
  rc=0
  wait "$pid" || rc=$?
  cat out.txt
  test "$rc" -eq 130 || fail "exit code $rc, expected 130"
  grep -q interrupted out.txt || fail "no word of the interrupt"
  test -p out/$name.png || fail "the FIFO was replaced"
  unchanged
}

refused_outputs() {
  step "a socket where a file of the set goes: refused, nothing of the set changes"
  previous_run
  rm out/$name.vti
  python3 -c 'import socket, sys; socket.socket(socket.AF_UNIX).bind(sys.argv[1])' out/$name.vti
  snapshot out > before.txt
  "$expect" 1 "cannot write \"out/$name.vti\": it is a socket" -- \
    "$asrt" trace "$scene" -r 16x16 -q --mass 0.5 -o out/
  test -S out/$name.vti || fail "the socket was replaced"
  unchanged

  step "a link to a device where a file goes: refused, not followed and not replaced"
  rm out/$name.vti
  ln -s /dev/null out/$name.vti
  snapshot out > before.txt
  "$expect" 1 "\"out/$name.vti\": it is a symbolic link to a character device" -- \
    "$asrt" trace "$scene" -r 16x16 -q --mass 0.5 -o out/
  test -L out/$name.vti || fail "the link was replaced"
  unchanged

  step "a prefix that is a device (-o /dev/null) is a usage error; nothing is made beside it"
  "$expect" 2 "--output: \"/dev/null\" is a character device" -- \
    "$asrt" trace "$scene" -r 16x16 -q -o /dev/null
  test -c /dev/null || fail "/dev/null is no longer a character device"
  for made in /dev/null.png /dev/null.vti /dev/null-hits.vtp; do
    test ! -e "$made" || fail "$made was made"
  done
  mkfifo prefix
  "$expect" 2 "--output: \"prefix\" is a FIFO" -- "$asrt" trace "$scene" -r 16x16 -q -o prefix
  test -p prefix || fail "the FIFO was replaced"
  test ! -e prefix.png || fail "prefix.png was made"
}

# Needs a throwaway server named by the PG* variables (asrtWithThrowawayPostgres).
show_through_devices() {
  step "a stored frame, exported to a regular file for reference"
  # The id as the store reports it: a sequence may skip values.
  id="$("$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace "$scene" -r 32x32 -q --store -o traced |
    "$here/stored-frame-id.sh")"
  test -n "$id" || fail "no frame id reported"
  "$asrt" show "$id" --png ref.png > /dev/null
  step "show writes through a FIFO, which stays a FIFO"
  mkfifo picture.png
  cat picture.png > captured &
  reader=$!
  "$expect" 0 "wrote picture.png" -- "$asrt" show "$id" --png picture.png --vti frame.vti
  test -p picture.png || { kill "$reader"; fail "the FIFO was replaced"; }
  wait_until stopped "$reader" || { kill "$reader"; fail "the FIFO's reader got no end of file"; }
  cmp captured ref.png || fail "the FIFO's reader did not get the picture"
  "$check" frame.vti=32x32
  step "show writes through /dev/null, which stays a character device"
  "$expect" 0 "wrote /dev/null" -- "$asrt" show "$id" --png /dev/null
  test -c /dev/null || fail "/dev/null is no longer a character device"
  step "a device that refuses the bytes (/dev/full): exit 1, the other file of the set unchanged"
  md5sum frame.vti > before.txt
  "$expect" 1 "cannot write \"/dev/full\": No space left on device" -- \
    "$asrt" show "$id" --where "image_order >= 1" --png /dev/full --vti frame.vti
  test -c /dev/full || fail "/dev/full is no longer a character device"
  md5sum -c before.txt || fail "frame.vti changed"
  test -z "$(ls -A | grep '\.part$')" || fail "a temporary was left: $(ls -A)"
}

# Needs a throwaway server named by the PG* variables (asrtWithThrowawayPostgres).
store_interrupt() {
  step "a first frame stored (the schema and a frame to keep)"
  "$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace "$scene" -r 8x8 -q --store=first -o first
  step "another session holds a lock on the frames table that makes the next insert wait"
  mkfifo sql.fifo
  psql -X -q -v ON_ERROR_STOP=1 < sql.fifo > psql.out 2>&1 &
  psql_pid=$!
  exec 4> sql.fifo
  echo "BEGIN; LOCK TABLE frames IN SHARE MODE; SELECT 'lock ' || 'held';" >&4
  wait_until grep -q "lock held" psql.out || fail "the lock was not taken: $(cat psql.out)"
  "$asrt" trace "$scene" -r 8x8 -q --mass 0.5 --store=second -o out/ > out.txt 2>&1 &
  pid=$!
  waiting_for_lock() {
    test "$(psql -X -A -t -c "SELECT count(*) FROM pg_stat_activity
      WHERE application_name = 'asrt' AND wait_event_type = 'Lock'")" -eq 1
  }
  wait_until waiting_for_lock || fail "asrt never waited for the lock: $(cat out.txt)"
  step "Ctrl-C while asrt waits: it stops with 130 and stores nothing"
  kill -INT "$pid"
  if ! wait_until stopped "$pid"; then
    # Released, the store goes ahead: the exit code and the frame count below tell.
    echo "asrt did not stop on Ctrl-C while storing; releasing the lock"
  fi
  echo "ROLLBACK;" >&4
  exec 4>&-
  wait "$psql_pid" || true
  rc=0
  wait "$pid" || rc=$?
  cat out.txt
  test "$rc" -eq 130 || fail "exit code $rc, expected 130"
  grep -q interrupted out.txt || fail "no word of the interrupt"
  if grep -q "stored as frame" out.txt; then fail "success printed for an interrupted store"; fi
  test "$("$asrt" list | tail -n +2 | wc -l)" -eq 1 || fail "a frame was stored: $("$asrt" list)"
  test ! -e out || test -z "$(ls -A out)" || fail "files of the interrupted frame: $(ls -A out)"
}

"$case_name"
echo "hostile-files $case_name: passed"
