#!/usr/bin/env bash
# Every kind of VTK XML file the asrt program writes (trace, a stored series, show, interpolate,
# bundle) must open in ParaView's own readers with the points its header promises: ParaView
# shows a file it cannot parse as an empty dataset, which no test of VTK's readers here notices.
# Runs under asrtWithThrowawayPostgres, whose PG* variables name the server --store uses.
# Usage: outputs-open-in-paraview.sh ASRT PVPYTHON SCENES_DIR WORK_DIR
set -euo pipefail
if [ $# -ne 4 ]; then
  echo "usage: $0 ASRT PVPYTHON SCENES_DIR WORK_DIR" >&2
  exit 2
fi
asrt="$1"; pvpython="$2"; scenes="$3"; work="$4"
reader="$(cd "$(dirname "$0")" && pwd)/read_outputs.py"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
fail() { echo "outputs-open-in-paraview: $*" >&2; exit 1; }

# Small frames, but not too small: a file under about 4 KB parses in one piece, so appended data
# (what ParaView 5.11 cannot read) would open anyway; at 24x18 every file is 6 KB or more.
step "trace: picture, frame, hits and rays"
"$asrt" trace "$scenes/kerr-disk.json" -r 24x18 --polylines=6 -q -o trace/

# Arrays of many compressed blocks (the largest at 200x150 spans 22 of 32 KiB), compressed on
# every thread with the compressor asrt writes with.
step "trace at 200x150: arrays of many LZ4 blocks"
"$asrt" trace "$scenes/kerr-disk.json" -r 200x150 --formats vti,vtp -q -o blocks/
for f in blocks/kerr-disk.vti blocks/kerr-disk-hits.vtp; do
  grep -q 'compressor="vtkLZ4DataCompressor"' "$f" || fail "$f is not LZ4-compressed"
done

step "a stored series: numbered files and .pvd collections"
"$asrt" trace "$scenes/fig4-mass-start.json" -r 24x18 --sweep mass=0.5:0.7:2 --polylines=6 \
  --store -q -o series/ramp | tee series.txt
# The ids the store gave, not ones assumed: the server may not start at 1.
mapfile -t ids < <(sed -n 's/^ *stored as frame \([0-9][0-9]*\).*/\1/p' series.txt)
[ "${#ids[@]}" -eq 2 ] || fail "the series should have stored 2 frames; trace said: $(cat series.txt)"
"$asrt" list | tee list.txt
for id in "${ids[@]}"; do
  awk -v id="$id" '$1 == id { found = 1 } END { exit !found }' list.txt ||
    fail "frame $id, stored by the series, is not in asrt list"
done

step "show: frame ${ids[0]} read back from the store"
mkdir -p show
"$asrt" show "${ids[0]}" --vti show/frame.vti --vtp show/frame-hits.vtp

step "interpolate: frames ${ids[0]} -> ${ids[1]}"
"$asrt" interpolate "${ids[0]}" "${ids[1]}" -n 2 -q -o interp/m

step "bundle: the rays as poly data"
# Rendering needs an X display; scripts/test runs the suite under xvfb-run.
display=()
if [ -z "${DISPLAY:-}" ]; then
  command -v xvfb-run > /dev/null || fail "bundle needs an X display: DISPLAY is unset, no xvfb-run"
  display=(xvfb-run -a -s "-screen 0 1280x1024x24 -noreset")
fi
"${display[@]}" "$asrt" bundle "$scenes/kerr-disk.json" -r 5x5 --size 160x120 \
  --vtp bundle/rays.vtp -q -o bundle/

step "every command wrote the kinds of file it promises"
# COMMAND_DIR KIND...: at least one file of each kind under the command's folder.
expect_kinds() {
  local dir="$1" kind; shift
  for kind in "$@"; do
    [ -n "$(find "$dir" -type f -name "*.$kind" -print -quit)" ] ||
      fail "$dir: no .$kind file written (found: $(find "$dir" -type f | sort | tr '\n' ' '))"
  done
}
expect_kinds trace vti vtp
expect_kinds blocks vti vtp
expect_kinds series vti vtp pvd
expect_kinds show vti vtp
expect_kinds interp vti pvd
expect_kinds bundle vtp

step "ParaView reads them all"
mapfile -t files < <(find . -type f \( -name '*.vti' -o -name '*.vtp' -o -name '*.pvd' \) | sort)
"$pvpython" "$reader" "${files[@]}" ||
  fail "some files asrt wrote do not open in ParaView ($pvpython); see above"
echo "outputs-open-in-paraview: ${#files[@]} files open in ParaView"
