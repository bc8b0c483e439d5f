#!/usr/bin/env bash
# asrt interpolate's path method: four key frames of the mass ramp of Figs. 4-5 traced from scene
# files, frames between them made per pixel to a quality target, each checked against the frame
# this script traces itself at that frame's mass; and the options' misuse refused.
# Usage: cli-interpolate-path.sh ASRT CHECKER EXPECT SCENES_DIR WORK_DIR
set -euo pipefail
asrt="$1"; check="$2"; expect="$3"; scenes="$4"; work="$5"
rm -rf "$work"; mkdir -p "$work"; cd "$work"
step() { echo "== $*"; }
# The scene at mass M, its textures found where the scene file's are.
sceneAt() {
  sed -e "s/\"mass\": 0.1/\"mass\": $1/" -e "s#\"\.\./textures/#\"$scenes/../textures/#" \
    "$scenes/fig4-mass-start.json" > "m$1.json"
}
for m in 0.65 0.7 0.75 0.8 0.675 0.725 0.775; do sceneAt "$m"; done

step "the path method to 35 dB: every frame between the keys reaches 34 dB against its trace"
"$expect" 0 "per pixel along the mass, quality target 35 dB" -- "$asrt" interpolate --scenes \
  m0.65.json m0.7.json m0.75.json m0.8.json -r 64x64 -n 1 --quality 35 -q -o path/
"$check" path/interpolated-006.png=64x64 path/interpolated.pvd=7 path/interpolated.ogv=7
for frame in 1:0.675 3:0.725 5:0.775; do
  n="${frame%%:*}"; m="${frame##*:}"
  "$asrt" trace "m$m.json" -r 64x64 --formats png -q -o "truth-$m" > /dev/null
  "$check" "path/interpolated-00$n.png:truth-$m.png>=34"
done
step "key frames are themselves"
"$asrt" trace m0.7.json -r 64x64 --formats png -q -o truth-0.7 > /dev/null
"$check" "path/interpolated-002.png:truth-0.7.png>=100"

step "40 dB, above the key frames' settings: their error traced converged, or held with --keep-settings"
"$expect" 0 "converged%" -- "$asrt" interpolate --scenes m0.65.json m0.7.json m0.75.json \
  m0.8.json -r 64x64 -n 1 --quality 40 -q -o raised/
# The picture that judges 40 dB: 8 x 8 filtered samples a pixel (asrt::convergedSideFor).
"$asrt" trace m0.725.json -r 64x64 --antialias filter --supersample 8 --formats png -q \
  -o conv8-0.725 > /dev/null
"$check" "raised/interpolated-003.png:conv8-0.725.png>=39"
"$expect" 0 "is above what the key frames' settings reach" -- "$asrt" interpolate --scenes \
  m0.65.json m0.7.json m0.75.json m0.8.json -r 64x64 -n 1 --quality 40 --keep-settings -q \
  -o kept/

step "misused options are refused before anything is traced"
"$expect" 2 "--quality goes with --method path" -- "$asrt" interpolate --scenes m0.65.json \
  m0.7.json --method splats --quality 35 -o bad/
"$expect" 2 "--exact goes with --method splats" -- "$asrt" interpolate --scenes m0.65.json \
  m0.7.json --quality 35 --exact -o bad/
"$expect" 2 "--keep-settings goes with --quality" -- "$asrt" interpolate --scenes m0.65.json \
  m0.7.json --keep-settings -o bad/
"$expect" 2 "--quality: the target must lie in \(0, 100\] dB" -- "$asrt" interpolate --scenes \
  m0.65.json m0.7.json --quality 0 -o bad/
"$expect" 2 "--quality: the target must lie in \(0, 100\] dB" -- "$asrt" interpolate --scenes \
  m0.65.json m0.7.json --quality 101 -o bad/
"$expect" 2 "--method: \"cubic\" is neither splats nor path" -- "$asrt" interpolate --scenes \
  m0.65.json m0.7.json --method cubic -o bad/
"$check" '!bad-000.png' '!bad/interpolated-000.png'
