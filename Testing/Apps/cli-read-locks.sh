#!/usr/bin/env bash
# Reads that meet a table another session holds locked (psql, in an open transaction, LOCK TABLE
# ... IN ACCESS EXCLUSIVE MODE, which blocks every read of it): asrt list, show and interpolate
# stop at once on Ctrl-C or SIGTERM with exit code 130, and give up after ASRT_LOCK_TIMEOUT with
# one line naming the table and exit code 3. Each case checks that psql still holds the lock when
# asrt has ended (asrt did not wait for it) and that no file was written. The lock is taken on
# frames (the commands wait in their first reads) or on ray_blocks (show waits in the reader, for
# the rays). Needs a throwaway server named by the PG* variables (asrtWithThrowawayPostgres).
# Usage: cli-read-locks.sh CASE ASRT EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
case_name="$1"; asrt="$2"; expect="$3"; scenes="$4"; work="$5/$1"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
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

# A frame to read (of fig2-no-hole, with ARGS... as overrides); sets frame to its id as the store
# reports it.
store_frame() {
  local out
  out="$("$expect" 0 "stored as frame [0-9]+" -- \
    "$asrt" trace "$scenes/fig2-no-hole.json" -r 8x8 -q "$@" --store -o traced)" || {
    echo "$out"
    return 1
  }
  frame="$("$here/stored-frame-id.sh" <<< "$out")"
}

# psql holds TABLE locked until release_lock, in a transaction fed through a FIFO.
hold_lock() {
  mkfifo sql.fifo
  psql -X -q -A -t -v ON_ERROR_STOP=1 < sql.fifo > psql.out 2>&1 &
  psql_pid=$!
  exec 4> sql.fifo
  echo "BEGIN; LOCK TABLE $1 IN ACCESS EXCLUSIVE MODE;
    SELECT 'lock held by ' || pg_backend_pid();" >&4
  wait_until grep -q "lock held by" psql.out || fail "the lock was not taken: $(cat psql.out)"
  locker="$(sed -n 's/^lock held by \([0-9]*\)$/\1/p' psql.out)"
  locked_table="$1"
}
release_lock() {
  echo "ROLLBACK;" >&4
  exec 4>&-
  wait "$psql_pid" || true
}
# Whether psql's session still holds the lock, as the server's lock table says.
lock_still_held() {
  test "$(psql -X -A -t -c "SELECT count(*) FROM pg_locks l JOIN pg_class c ON c.oid = l.relation
    WHERE l.granted AND l.mode = 'AccessExclusiveLock' AND c.relname = '$locked_table'
    AND l.pid = $locker")" -eq 1
}
waiting_for_lock() {
  test "$(psql -X -A -t -c "SELECT count(*) FROM pg_stat_activity
    WHERE application_name = 'asrt' AND wait_event_type = 'Lock'")" -eq 1
}

# Starts asrt ARGS... in the background (stdout and stderr apart) and waits until it waits for
# the lock; sets pid. No lock timeout: only the signal can end the wait.
start_waiting() {
  ASRT_LOCK_TIMEOUT=0 "$asrt" "$@" > out.txt 2> err.txt &
  pid=$!
  wait_until waiting_for_lock || {
    kill -KILL "$pid"
    fail "asrt never waited for the lock: $(cat out.txt err.txt)"
  }
}

# Waits for asrt to end by itself, the lock still held; sets rc.
wait_for_end() {
  if ! wait_until stopped "$pid"; then
    kill -KILL "$pid"
    release_lock
    fail "asrt was still waiting for the lock: $1"
  fi
  rc=0
  wait "$pid" || rc=$?
  cat out.txt err.txt
  lock_still_held || fail "psql no longer holds the lock"
}

# SIGNAL (INT or TERM) while asrt ARGS... waits for the lock on TABLE: exit 130 at once, the
# interrupt said, nothing written.
interrupted_while_waiting() {
  local signal="$1" table="$2"; shift 2
  hold_lock "$table"
  step "SIG$signal while asrt $1 waits for the lock on $table"
  start_waiting "$@"
  kill "-$signal" "$pid"
  wait_for_end "SIG$signal did not stop it"
  release_lock
  test "$rc" -eq 130 || fail "exit code $rc, expected 130"
  grep -q "interrupted" err.txt || fail "no word of the interrupt"
  test ! -e x.png || fail "x.png was written"
  test ! -e out || test -z "$(ls -A out)" || fail "files were written: $(ls -A out)"
  test -z "$(ls -A | grep '\.part$')" || fail "a temporary was left: $(ls -A)"
}

# asrt ARGS... gives up waiting for the lock on TABLE after ASRT_LOCK_TIMEOUT: exit 3, one line
# on stderr naming the table, nothing written.
gives_up_on() {
  local table="$1"; shift
  hold_lock "$table"
  step "asrt $1 with ASRT_LOCK_TIMEOUT=0.5 while $table is locked"
  ASRT_LOCK_TIMEOUT=0.5 "$asrt" "$@" > out.txt 2> err.txt &
  pid=$!
  wait_for_end "it did not give up"
  release_lock
  test "$rc" -eq 3 || fail "exit code $rc, expected 3"
  test "$(wc -l < err.txt)" -eq 1 || fail "stderr has $(wc -l < err.txt) lines, expected one"
  local said="the $table table is locked by another session; gave up after 0\.5 s"
  grep -Eq "^asrt $1: database: .*: $said\$" err.txt ||
    fail "the message does not name the locked table and the wait"
  test ! -e x.png || fail "x.png was written"
}

list_sigint() { store_frame; interrupted_while_waiting INT frames list; }
list_sigterm() { store_frame; interrupted_while_waiting TERM frames list; }
show_sigint() { store_frame; interrupted_while_waiting INT frames show "$frame" --png x.png; }
show_sigterm() { store_frame; interrupted_while_waiting TERM frames show "$frame" --png x.png; }
# The frame's row is read; the reader waits for its rays.
show_rays_sigint() {
  store_frame; interrupted_while_waiting INT ray_blocks show "$frame" --png x.png
}
interpolate_sigint() {
  store_frame
  local first="$frame"
  store_frame --mass 0.5
  interrupted_while_waiting INT frames interpolate "$first" "$frame" -n 3 -o out/
}
list_lock_timeout() { store_frame; gives_up_on frames list; }
show_rays_lock_timeout() { store_frame; gives_up_on ray_blocks show "$frame" --png x.png; }

bad_lock_timeout() {
  step "ASRT_LOCK_TIMEOUT that is no number of seconds: a usage error naming it"
  ASRT_LOCK_TIMEOUT=soon "$expect" 2 "ASRT_LOCK_TIMEOUT: 'soon' is not a number" -- "$asrt" list
  ASRT_LOCK_TIMEOUT=-1 "$expect" 2 "ASRT_LOCK_TIMEOUT: '-1' is not a number of seconds" -- \
    "$asrt" list
}

"$case_name"
echo "cli-read-locks $case_name: passed"
