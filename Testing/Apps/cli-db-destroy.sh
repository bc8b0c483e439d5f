#!/usr/bin/env bash
# asrt db --dir D destroy deletes only a cluster ASRT made: a folder that merely holds a
# PG_VERSION, a real cluster with a file of someone else's at its top, or an unmarked cluster
# (as an older asrt made them) is refused and left as it was; a marked cluster is destroyed.
# The clusters go under a fresh folder of /tmp that the server's user (postgres, when root runs
# the tests) can enter.
# Usage: cli-db-destroy.sh ASRT EXPECT
set -euo pipefail
asrt="$1"; expect="$2"
step() { echo "== $*"; }
fail() { echo "FAILED: $*" >&2; exit 1; }
top=$(mktemp -d /tmp/asrt-db-XXXXXX)
chmod 755 "$top"
trap '"$asrt" db --dir "$top/real" stop > /dev/null 2>&1 || true; rm -rf "$top"' EXIT
# The names and checksums of a folder's files, hidden ones included.
snapshot() {
  (cd "$1" &&
    find . -print0 | LC_ALL=C sort -z | xargs -0 ls -ld --time-style=+ | awk '{print $1, $NF}' &&
    find . -type f -print0 | LC_ALL=C sort -z | xargs -0 -r md5sum)
}

step "a folder holding a PG_VERSION and a precious file is refused and left intact"
fake="$top/fake"
mkdir "$fake"
echo 15 > "$fake/PG_VERSION"
echo "three years of work" > "$fake/thesis.tex"
snapshot "$fake" > "$top/fake-before.txt"
"$expect" 4 "refusing to destroy $fake: it has no ASRT_CLUSTER marker, so ASRT did not make it" -- \
  "$asrt" db --dir "$fake" destroy
snapshot "$fake" | diff "$top/fake-before.txt" - || fail "the folder changed"

step "a marked folder that is no whole cluster is refused"
touch "$fake/ASRT_CLUSTER"
"$expect" 4 "refusing to destroy $fake: it has no postgresql.conf" -- \
  "$asrt" db --dir "$fake" destroy
test -f "$fake/thesis.tex" || fail "the folder lost a file"

step "a cluster made by asrt db start carries the marker"
real="$top/real"
"$expect" 0 "host=" -- "$asrt" db --dir "$real" start
test -f "$real/ASRT_CLUSTER" || fail "no marker in the new cluster"

step "a file of someone else's at the top of the cluster: refused, the server untouched"
echo "not the cluster's" > "$real/notes.txt"
"$expect" 4 "refusing to destroy $real: 'notes.txt' in it is not part of a PostgreSQL cluster" -- \
  "$asrt" db --dir "$real" destroy
test "$(cat "$real/notes.txt")" = "not the cluster's" || fail "notes.txt changed"
"$expect" 0 "running" -- "$asrt" db --dir "$real" status
rm "$real/notes.txt"

step "an unmarked cluster, as an older asrt left them: refused with advice; start marks it"
rm "$real/ASRT_CLUSTER"
"$expect" 4 "made by an older ASRT.*asrt db start" -- "$asrt" db --dir "$real" destroy
test -d "$real/base" || fail "the cluster lost its data"
"$expect" 0 "host=" -- "$asrt" db --dir "$real" start
test -f "$real/ASRT_CLUSTER" || fail "start did not mark the cluster"

step "the marked cluster is destroyed"
"$expect" 0 "removed $real" -- "$asrt" db --dir "$real" destroy
test ! -e "$real" || fail "$real is still there"
"$expect" 3 "not running" -- "$asrt" db --dir "$real" status
test -f "$fake/thesis.tex" || fail "the other folder lost a file"
echo "cli-db-destroy: all steps passed"
