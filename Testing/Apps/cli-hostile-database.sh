#!/usr/bin/env bash
# asrt against a database used in the ways that must not hurt it, on a throwaway server that
# asrtWithThrowawayPostgres started and named in the PG* variables (a superuser, as on the private
# server): reading commands pointed at a database that is not ASRT's, a frame already stored
# (refused before its trace), the hostile --where predicates of Testing/Data/hostile, a frame row
# edited to an impossible size, a role without CREATEROLE, and two --replace stores of one frame
# at once.
# Usage: cli-hostile-database.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR HOSTILE_DIR
set -euo pipefail
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"; hostile="$6"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
sql() { psql -X -q -At -v ON_ERROR_STOP=1 "$@"; }
scene="$scenes/fig2-no-hole.json"

step "reading commands on a database that is not ASRT's create nothing in it"
sql -c "CREATE DATABASE unrelated"
sql -d unrelated -c "CREATE TABLE someone_elses (x int)"
"$expect" 3 "holds no ASRT schema.*asrt db init.*asrt trace --store" -- \
  "$asrt" list --db "dbname=unrelated"
"$expect" 3 "holds no ASRT schema" -- "$asrt" show 1 --db "dbname=unrelated"
"$expect" 3 "holds no ASRT schema" -- "$asrt" show 1 --png x.png --db "dbname=unrelated"
"$expect" 3 "holds no ASRT schema" -- "$asrt" interpolate 1 2 -q -o interpolated/ \
  --db "dbname=unrelated"
test "$(sql -d unrelated -c "SELECT string_agg(relname, ',') FROM pg_class
  WHERE relnamespace = 'public'::regnamespace")" = someone_elses
step "asrt db init makes the schema, once"
"$expect" 0 "schema version 9 created; predicates run as the role asrt_predicate" -- \
  "$asrt" db init --db "dbname=unrelated"
"$expect" 0 "schema version 9 already in place" -- "$asrt" db init --db "dbname=unrelated"
"$expect" 0 "no frames stored yet" -- "$asrt" list --db "dbname=unrelated"
"$expect" 2 "--db goes with init only" -- "$asrt" db status --db "dbname=unrelated"

step "a frame already stored is refused before it is traced: no file is written"
# Ids come from the server's sequence, which may skip values: the stored frame's is read, and the
# sequence is moved on first so that an id assumed to be 1 would be wrong.
"$expect" 0 "schema version [0-9]+ created" -- "$asrt" db init
sql -c "SELECT setval(pg_get_serial_sequence('frames', 'id'), 41)"
out="$("$expect" 0 "stored as frame [0-9]+" -- "$asrt" trace "$scene" -r 8x8 -q --store=first \
  -o first)" || { echo "$out"; exit 1; }
id="$("$(dirname "$0")/stored-frame-id.sh" <<< "$out")"
"$expect" 3 "already stored as frame $id \(label \"first\"\) \(add --replace to store it again\)" \
  -- "$asrt" trace "$scene" -r 8x8 -q --store=again -o again
"$check" '!again.png' '!again.vti' '!again-hits.vtp'
step "in a series, the frame before the stored one is traced and stored, the stored one is not"
out="$("$expect" 3 "already stored as frame $id" -- "$asrt" trace "$scene" -r 8x8 -q \
  --store=ramp --sweep mass=0.5:0:2 -o ramp)" || { echo "$out"; exit 1; }
ramp="$("$(dirname "$0")/stored-frame-id.sh" <<< "$out")"
"$check" ramp-000.png=8x8 '!ramp-001.png'
test "$("$asrt" list | tail -n +2 | wc -l)" -eq 2

step "hostile --where predicates are refused with exit code 3, select nothing and harm nothing"
sql -c "CREATE EXTENSION IF NOT EXISTS dblink"
# Another session, as a concurrent asrt trace --store would be: it must survive every predicate.
coproc VICTIM { psql -X -q -At; }
victimPid() {
  echo "SELECT pg_backend_pid();" >&"${VICTIM[1]}"
  local pid; read -r -t 30 pid <&"${VICTIM[0]}"; echo "$pid"
}
victim="$(victimPid)"
rm -f /tmp/asrt-hostile-copy-to-program /tmp/asrt-hostile-lo-export
count=0
while IFS= read -r predicate; do
  case "$predicate" in '' | '#'*) continue ;; esac
  if ! "$expect" 3 "the ray predicate was refused" -- \
    "$asrt" show "$id" --where "$predicate" --png hostile.png > out.txt; then
    cat out.txt; exit 1
  fi
  grep "^asrt show:" out.txt
  if grep -q "root:" out.txt; then echo "a file's content was shown: $predicate"; exit 1; fi
  test "$(victimPid)" = "$victim"
  count=$((count + 1))
done < "$hostile/predicates.txt"
test "$count" -ge 40
victimProcess=$VICTIM_PID
echo '\q' >&"${VICTIM[1]}"
wait "$victimProcess"
"$check" '!hostile.png'
test ! -e /tmp/asrt-hostile-copy-to-program
test ! -e /tmp/asrt-hostile-lo-export
test "$(sql -c "SELECT count(*) FROM frames")" = 2
step "ordinary predicates still select rays"
"$expect" 0 "wrote picked.png" -- "$asrt" show "$id" --png picked.png --where "i < 4 AND abs(j) >= 0"
"$check" '~picked.png=8x8'

step "a frame row edited to a size no read can allocate is one line and exit code 3"
oneLine="$(dirname "$0")/expect-one-line-error.sh"
for size in "width = 100000, height = 100000" "width = 2147483647, height = 1"; do
  sql -c "UPDATE frames SET $size WHERE id = $id"
  "$oneLine" 3 "frame $id is inconsistent: frames.width x frames.height = [0-9]+ x [0-9]+ is more than the 268435456 pixels \(2\^28\)" \
    -- "$asrt" show "$id" --png edited.png
  "$oneLine" 3 "frame $id is inconsistent: frames.width x frames.height" \
    -- "$asrt" interpolate "$id" "$ramp" -q -o edited/
done
sql -c "UPDATE frames SET width = 8, height = 8 WHERE id = $id"
"$check" '!edited.png'
"$expect" 0 "wrote edited.png" -- "$asrt" show "$id" --png edited.png

step "a role without CREATEROLE is told what to do, and doing it is enough"
sql -c "CREATE ROLE asrt_plain LOGIN" -c "CREATE DATABASE plain OWNER asrt_plain"
"$expect" 3 "needs a superuser or a role with CREATEROLE.*run GRANT asrt_predicate TO \"asrt_plain\";" \
  -- "$asrt" db init --db "dbname=plain user=asrt_plain"
test "$(sql -d plain -c "SELECT count(*) FROM pg_class WHERE relnamespace = 'public'::regnamespace")" = 0
sql -c "GRANT asrt_predicate TO asrt_plain"
"$expect" 0 "schema version 9 created" -- "$asrt" db init --db "dbname=plain user=asrt_plain"

step "two --replace stores of one frame at once: the one that loses is told what happened"
# A second session stands in for the winner: it holds the first frame deleted in an open transaction, the
# store with --replace waits for that row, then the winner puts its own frame of the same identity
# in its place and commits.
coproc WINNER { psql -X -q -At -v ON_ERROR_STOP=1; }
echo "BEGIN; CREATE TEMP TABLE keep AS SELECT * FROM frames WHERE id = $id;
  DELETE FROM frames WHERE id = $id; SELECT 'held';" >&"${WINNER[1]}"
read -r -t 30 line <&"${WINNER[0]}"; test "$line" = held
"$asrt" trace "$scene" -r 8x8 -q --store=loser --replace -o loser > loser.txt 2>&1 &
loser=$!
waiting=0
for _ in $(seq 1 600); do
  waiting="$(sql -c "SELECT count(*) FROM pg_stat_activity WHERE application_name = 'asrt'
    AND wait_event_type = 'Lock'")"
  if [ "$waiting" = 1 ]; then break; fi
  sleep 0.1
done
test "$waiting" = 1
echo "UPDATE keep SET id = (SELECT max(id) + 1000 FROM frames), label = 'winner';
  INSERT INTO frames SELECT * FROM keep; COMMIT; SELECT 'done';" >&"${WINNER[1]}"
read -r -t 30 line <&"${WINNER[0]}"; test "$line" = done
rc=0; wait "$loser" || rc=$?
cat loser.txt
test "$rc" -eq 3
grep -q "another writer stored this scene with these parameters at the same time" loser.txt
if grep -q -- "--replace" loser.txt; then echo "told to add --replace, which it gave"; exit 1; fi
test "$(sql -c "SELECT label FROM frames WHERE frame_hash = (SELECT frame_hash FROM frames
  WHERE label = 'winner')")" = winner

step "the private server's own database is ASRT's: reading it sets the schema up there"
# In a fresh folder of /tmp that the server's user can enter, wherever the build folder lies.
private_top=$(mktemp -d /tmp/asrt-db-XXXXXX)
chmod 755 "$private_top"
private="$private_top/private"
trap '"$asrt" db --dir "$private" destroy > /dev/null 2>&1 || true; rm -rf "$private_top"' EXIT
(
  unset PGHOST PGPORT PGDATABASE PGUSER
  export ASRT_DB_DIR="$private"
  "$expect" 0 "no frames stored yet" -- "$asrt" list
  "$expect" 0 "schema version 9 already in place" -- "$asrt" db init
)
echo "cli-hostile-database: all steps passed"
