#!/usr/bin/env bash
# asrt trace writes the same bytes on one OpenMP thread as on several: the frame is traced the same,
# and the arrays of the .vti and -hits.vtp, whose blocks are compressed on every thread, are
# compressed into the same file.
# Usage: cli-thread-count-outputs.sh ASRT SCENE WORK_DIR
set -euo pipefail
if [ $# -ne 3 ]; then
  echo "usage: $0 ASRT SCENE WORK_DIR" >&2
  exit 2
fi
asrt="$1"; scene="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
for threads in 1 2 3; do
  OMP_NUM_THREADS=$threads "$asrt" trace "$scene" -r 200x150 --formats png,vti,vtp -q -o "t$threads"
done
for threads in 2 3; do
  for file in .png .vti -hits.vtp; do
    cmp "t1$file" "t$threads$file" ||
      { echo "cli-thread-count-outputs: $file differs between 1 and $threads threads" >&2; exit 1; }
  done
done
echo "cli-thread-count-outputs: the files are the same on 1, 2 and 3 threads"
