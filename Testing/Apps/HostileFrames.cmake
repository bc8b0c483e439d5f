# Hostile-input CLI tests: Frames. Frames that would silently be wrong (rays ending on the step
# budget or in numerical failure, a camera the scene file could not hold) and messages that would
# mislead (an overflowing value reported as what it breaks, VTK's own coloured lines beside the
# error). Every frame is 8 × 8 pixels.
set(frames_work "${CMAKE_CURRENT_BINARY_DIR}/hostile-frames")
set(one_line_error "${CMAKE_CURRENT_SOURCE_DIR}/expect-one-line-error.sh")
# asrt_frames_test(NAME "SPECS" CODE PATTERN ARGS...): asrt trace ARGS -r 8x8 -o out, in a fresh
# directory, exits with CODE, its output matches PATTERN, and the files are as SPECS say.
function (asrt_frames_test name specs code pattern)
  asrt_output_test(CLI.Frames.${name} cli "${specs}"
    ${expect} ${code} "${pattern}" -- ${asrt} trace ${ARGN} -r 8x8 -q -o out)
endfunction ()
set(no_files "!out.png;!out.vti;!out-hits.vtp")

# A Kerr hole a millionth the size of the scene: its step is in units of M, so the rays end as
# around a hole of mass 1, not on the step budget.
asrt_frames_test(TinyKerrHole "out.png=8x8" 0
  "kerr-disk: 64 rays, 0 failed numerically, 0 out of steps"
  "${scenes}/kerr-disk.json" --mass 1e-6 --spin 1e-7)
# An override passes the scene file's checks: the eye must be inside the celestial sphere.
asrt_frames_test(CameraOutsideTheSky "${no_files}" 4
  "objects\\[0\\]\\.radius: the celestial sphere is seen from inside" "${scenes}/kerr-disk.json"
  --camera 0,-2000,0)
# Every ray fails: the frame is refused and nothing written, unless asked for (then the picture
# is the failure colour alone).
asrt_frames_test(HugeStepIsRefused "${no_files}" 1
  "failed share is 100 % \\(64 of 64 rays failed numerically.*--max-failed-share 1"
  "${scenes}/fig1-cylinders.json" --method DormandPrince54 --step 1e300)
asrt_frames_test(HugeStepAcceptedOnRequest "~out.png=8x8;~out.vti=8x8" 0
  "64 rays, 64 failed numerically.*at most 100 % allowed" "${scenes}/fig1-cylinders.json"
  --method DormandPrince54 --step 1e300 --max-failed-share 1)
asrt_frames_test(FailedShareOutOfRange "${no_files}" 2 "--max-failed-share: must be a fraction"
  "${scenes}/fig1-cylinders.json" --max-failed-share 1.5)
# Overflowing values are named with their bound, not as the horizon or view-up they break.
asrt_frames_test(HugeMass "${no_files}" 4 "^asrt trace: spacetime\\.mass: must be at most 1e\\+75"
  "${scenes}/fig1-cylinders.json" --mass 1e308)
asrt_frames_test(FarCamera "${no_files}" 4
  "^asrt trace: camera\\.position: coordinates must be at most 1e\\+75"
  "${scenes}/fig1-cylinders.json" --camera 1e308,0,0)
asrt_frames_test(TinyMass "${no_files}" 4 "spacetime\\.mass: must be 0 or at least 1e-75"
  "${scenes}/fig1-cylinders.json" --mass 1e-300)
asrt_frames_test(EmptyFormatList "${no_files}" 2 "--formats: the list is empty"
  "${scenes}/fig1-cylinders.json" --formats=)

# One plain line on stderr, even where VTK itself has something to say: a texture no reader
# recognises has the image factory's readers warn as they try it, and VTK's logger would print
# those in ANSI colours for a terminal-like TERM.
file(WRITE "${frames_work}/not-an-image.png" "this is text, not a PNG\n")
file(WRITE "${frames_work}/text-texture.json" "{\"spacetime\": {\"mass\": 1},
 \"camera\": {\"position\": [0, -30, 8], \"focalPoint\": [0, 0, 0]},
 \"objects\": [{\"type\": \"sphere\", \"id\": 1, \"center\": [0, 5, 0], \"radius\": 1,
                \"texture\": {\"image\": \"not-an-image.png\"}}]}")
add_test(NAME CLI.Frames.OneLineErrorForAnUnreadableTexture
  COMMAND ${CMAKE_COMMAND} -E env TERM=xterm-256color
    bash ${one_line_error} 4 "not-an-image\\.png" --
      ${asrt} trace "${frames_work}/text-texture.json" -r 8x8 -q -o "${frames_work}/out")
add_test(NAME CLI.Frames.OneLineErrorForAHugeMass
  COMMAND ${CMAKE_COMMAND} -E env TERM=xterm-256color
    bash ${one_line_error} 4 "spacetime\\.mass" --
      ${asrt} trace "${scenes}/fig1-cylinders.json" --mass 1e308 -r 8x8 -q -o "${frames_work}/out")
add_test(NAME CLI.Frames.OneLineErrorForAFailedFrame
  COMMAND ${CMAKE_COMMAND} -E env TERM=xterm-256color
    bash ${one_line_error} 1 "failed share" --
      ${asrt} trace "${scenes}/fig1-cylinders.json" --method DormandPrince54 --step 1e300 -r 8x8 -q -o "${frames_work}/out")
set_tests_properties(CLI.Frames.OneLineErrorForAnUnreadableTexture CLI.Frames.OneLineErrorForAHugeMass
  CLI.Frames.OneLineErrorForAFailedFrame PROPERTIES LABELS cli TIMEOUT 120)
