#!/usr/bin/env bash
# asrt runs its OpenMP threads with the passive wait policy unless the user chose one: libgomp
# itself reports the spin count it took (OMP_DISPLAY_ENV=verbose prints it as it loads, once: the
# launcher sets the policy before the program's libraries load, AsrtLauncher.cxx).
# Usage: cli-wait-policy.sh ASRT
set -euo pipefail
if [ $# -ne 1 ]; then
  echo "usage: $0 ASRT" >&2
  exit 2
fi
asrt="$1"
spin_counts() { # the GOMP_SPINCOUNT values libgomp reported, one a line, for env "$@"
  env OMP_DISPLAY_ENV=verbose "$@" "$asrt" --version 2>&1 | sed -n "s/^ *GOMP_SPINCOUNT = '\([0-9]*\)'.*/\1/p"
}
fail() { echo "cli-wait-policy: $*" >&2; exit 1; }

unset OMP_WAIT_POLICY GOMP_SPINCOUNT
counts=$(spin_counts)
[ "$(echo "$counts" | wc -l)" = 1 ] || fail "libgomp loaded more than once: '$counts'"
[ "$counts" = 0 ] || fail "without OMP_WAIT_POLICY, the spin count used is '$counts', not 0 (passive)"

counts=$(spin_counts OMP_WAIT_POLICY=active)
[ "$(echo "$counts" | wc -l)" = 1 ] || fail "OMP_WAIT_POLICY=active: libgomp loaded more than once"
[ "$counts" != 0 ] || fail "OMP_WAIT_POLICY=active was not kept (spin count 0)"

counts=$(spin_counts GOMP_SPINCOUNT=1234)
[ "$counts" = 1234 ] || fail "GOMP_SPINCOUNT=1234 was not kept: '$counts'"

"$asrt" --version | grep -q '^asrt ' || fail "asrt --version printed no version"
echo "cli-wait-policy: passive by default, the user's OMP_WAIT_POLICY and GOMP_SPINCOUNT kept"
