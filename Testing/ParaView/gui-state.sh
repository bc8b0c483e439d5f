#!/usr/bin/env bash
# The example state file in ParaView's GUI (needs a display: the suite runs under xvfb-run).
# 1. paraview loads Examples/paraview_kerr_disk.pvsm with the plugin from PV_PLUGIN_PATH and
#    compares its active view (the traced picture) with a baseline image (--test-baseline); it
#    exits 1 on a mismatch, writing what it saw into WORK.
# 2. A screenshot of the whole layout through the GUI's Python (--script) must not be blank: the
#    picture and the ray bundle are there.
# Usage: gui-state.sh PARAVIEW PVPYTHON PLUGIN_DIR SOURCE_DIR BASELINE WORK
set -euo pipefail
paraview=$1 pvpython=$2 plugin_dir=$3 source_dir=$4 baseline=$5 work=$6
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"
mkdir -p "$work"
export PV_PLUGIN_PATH="$plugin_dir"
# The state names its scene relative to the source tree's root, as the README says to run it.
cd "$source_dir"

echo "<pqevents></pqevents>" > "$work/empty.xml"
echo "== the state against the baseline"
"$paraview" --dr --state=Examples/paraview_kerr_disk.pvsm --test-script="$work/empty.xml" \
  --test-baseline="$baseline" --test-directory="$work" --exit > "$work/baseline.log" 2>&1 || {
  cat "$work/baseline.log"
  echo "gui-state: the GUI's view differs from $baseline (what it saw is in $work)" >&2
  exit 1
}
grep -q "No such file\|Error parsing\|No proxy that matches" "$work/baseline.log" && {
  cat "$work/baseline.log"
  echo "gui-state: the state did not load cleanly" >&2
  exit 1
}

echo "== a screenshot of the whole layout"
cat > "$work/shot.py" <<PY
from paraview.simple import GetLayout, LoadState, Render, SaveScreenshot, GetRenderViews
LoadState("Examples/paraview_kerr_disk.pvsm")
for view in GetRenderViews():
    Render(view)
SaveScreenshot("$work/layout.png", GetLayout(), ImageResolution=[800, 300])
PY
"$paraview" --dr --script="$work/shot.py" --exit > "$work/shot.log" 2>&1 || {
  cat "$work/shot.log"
  exit 1
}
"$pvpython" "$here/check_screenshot.py" "$work/layout.png"
echo "gui-state: passed"
