# Hostile-input CLI tests: Inputs. Textures that are corrupt, truncated or claim a huge size;
# scene JSON nested without end or holding huge values; scene files without end; series and sizes
# beyond their caps. Each must end in one clear line and its exit code (4 bad input, 2 usage),
# never a signal, and write nothing.
#
# The committed corpus, in ${hostile} (made by a few lines of Python with zlib; CRCs are zlib's):
#   png-truncated.png    the first third (275 bytes) of Data/textures/checker.png
#   png-bad-crc.png      checker.png with the CRC of its IDAT chunk inverted
#   png-garbage.png      checker.png's IHDR, then an IDAT of 400 random bytes with a valid CRC
#   png-huge-header.png  a valid IHDR of 60000 x 60000 RGB pixels, then 1000 deflated zero bytes
#   texture-NAME.json    an 8 x 8 scene whose celestial sphere shows png-NAME.png
#   texture-truncated-galaxy.json  the same for truncated-galaxy.png, made at test time below
#   ppm-short.ppm        100 bytes: a binary PPM header declaring 16384 x 16384 pixels, then 81
#   mhd-fifo.mhd         a 64 x 64 MetaImage header whose data file is a FIFO made at test time
#   texture-ppm-short.json, texture-mhd-fifo.json  scenes showing them
# Bigger inputs are made here (deep and long JSON) or at test time (/dev/zero, an endless pipe,
# the first third of galaxy.png).

# asrt_hostile_input_test(NAME CODE PATTERN [SETUP shell-commands] ARGS...): in a fresh directory,
# after the SETUP commands if any, asrt ARGS exits with CODE and prints PATTERN, and leaves no
# out.png, out.vti, out-hits.vtp. An 8 GB address-space limit turns an unbounded allocation into
# a failed test instead of an exhausted machine.
function (asrt_hostile_input_test name code pattern)
  cmake_parse_arguments(PARSE_ARGV 3 arg "" "SETUP" "")
  set(setup "${arg_SETUP}")
  if (setup)
    set(setup "${setup} && ")
  endif ()
  add_test(NAME CLI.Hostile.Inputs.${name}
    COMMAND ${run_and_check} "${work}/Hostile.Inputs.${name}" ${check}
      "!out.png" "!out.vti" "!out-hits.vtp" --
      bash -c "${setup}ulimit -v 8000000 && exec \"$@\"" hostile-input
        ${expect} ${code} "${pattern}" -- ${asrt} ${arg_UNPARSED_ARGUMENTS})
  set_tests_properties(CLI.Hostile.Inputs.${name} PROPERTIES LABELS cli TIMEOUT 60)
endfunction ()

# Textures: decoded by libpng (never VTK's PNG reader, which crashes on these), their declared
# size checked before any pixel is decoded. The texture field and the file are named.
set(texture_error "objects\\[0\\]\\.texture\\.image: cannot read \"png-")
foreach (command trace bundle)
  asrt_hostile_input_test(Texture.Truncated.${command} 4
    "${texture_error}truncated.png\".*corrupt or truncated PNG data \\(libpng: Read Error\\)"
    ${command} "${hostile}/texture-truncated.json" -o out.png)
  asrt_hostile_input_test(Texture.BadCrc.${command} 4
    "${texture_error}bad-crc.png\".*corrupt or truncated PNG data \\(libpng: IDAT: CRC error\\)"
    ${command} "${hostile}/texture-bad-crc.json" -o out.png)
  asrt_hostile_input_test(Texture.Garbage.${command} 4
    "${texture_error}garbage.png\".*corrupt or truncated PNG data \\(libpng: IDAT:"
    ${command} "${hostile}/texture-garbage.json" -o out.png)
  asrt_hostile_input_test(Texture.HugeHeader.${command} 4
    "${texture_error}huge-header.png\".*declares 60000 x 60000 pixels; image textures may have at most 16384 pixels a side"
    ${command} "${hostile}/texture-huge-header.json" -o out.png)
endforeach ()
file(SIZE "${PROJECT_SOURCE_DIR}/Data/textures/galaxy.png" galaxy_size)
math(EXPR galaxy_third "${galaxy_size} / 3")
foreach (command trace bundle)
  asrt_hostile_input_test(Texture.TruncatedGalaxy.${command} 4
    "texture\\.image: cannot read \"truncated-galaxy\\.png\".*\\(libpng: Read Error\\)"
    SETUP "head -c ${galaxy_third} '${PROJECT_SOURCE_DIR}/Data/textures/galaxy.png' > truncated-galaxy.png && cp '${hostile}/texture-truncated-galaxy.json' ."
    ${command} texture-truncated-galaxy.json -o out.png)
endforeach ()

# Textures other than PNG and JPEG are refused by name before they are opened: a 100-byte PPM
# declaring 16384 x 16384 pixels (VTK's reader took 1 GB and gave black for the rest), and a
# MetaImage whose data file is a FIFO nobody writes to (VTK's reader waited for ever).
foreach (command trace bundle)
  asrt_hostile_input_test(Texture.ShortPpm.${command} 4
    "texture\\.image: cannot read \"ppm-short\\.ppm\".*is not a PNG or JPEG file \\(extension \"\\.ppm\"\\)"
    ${command} "${hostile}/texture-ppm-short.json" -o out.png)
  asrt_hostile_input_test(Texture.MetaImageWithAFifo.${command} 4
    "texture\\.image: cannot read \"mhd-fifo\\.mhd\".*is not a PNG or JPEG file \\(extension \"\\.mhd\"\\)"
    SETUP "cp '${hostile}/mhd-fifo.mhd' '${hostile}/texture-mhd-fifo.json' . && mkfifo mhd-fifo.raw"
    ${command} texture-mhd-fifo.json -o out.png)
endforeach ()

# JSON nested 100000 deep, as the document and where a number belongs: refused while parsing
# (printing such a value in a message used to overflow the stack).
set(generated "${CMAKE_CURRENT_BINARY_DIR}/hostile-inputs")
string(REPEAT "[" 100000 deep_open)
string(REPEAT "]" 100000 deep_close)
file(WRITE "${generated}/deep-document.json" "${deep_open}${deep_close}")
file(WRITE "${generated}/deep-field.json"
  "{\"spacetime\": {\"mass\": ${deep_open}${deep_close}}, \"camera\": {}, \"objects\": []}")
string(REPEAT "{\"a\": " 100000 deep_objects)
string(REPEAT "}" 100000 deep_objects_close)
file(WRITE "${generated}/deep-objects.json" "${deep_objects}1${deep_objects_close}")
asrt_hostile_input_test(Json.DeepDocument 4
  "deep-document.json: \\[0\\]\\[0\\].*: arrays and objects nested more than 64 levels deep"
  trace "${generated}/deep-document.json" -o out)
asrt_hostile_input_test(Json.DeepField 4
  "deep-field.json: spacetime\\.mass\\[0\\].*: arrays and objects nested more than 64 levels deep"
  trace "${generated}/deep-field.json" -o out)
asrt_hostile_input_test(Json.DeepObjects 4
  "deep-objects.json: a\\.a\\.a.*: arrays and objects nested more than 64 levels deep"
  bundle "${generated}/deep-objects.json" -o out.png)
# A 100000-character unknown key and object type: quoted cut short.
string(REPEAT "x" 100000 long_text)
file(WRITE "${generated}/long-key.json"
  "{\"spacetime\": {\"mass\": 1, \"${long_text}\": 2}, \"camera\": {}, \"objects\": []}")
file(WRITE "${generated}/long-type.json" "{\"spacetime\": {\"mass\": 1},
 \"camera\": {\"position\": [0, -30, 8], \"focalPoint\": [0, 0, 0]},
 \"objects\": [{\"type\": \"${long_text}\"}]}")
asrt_hostile_input_test(Json.LongKeyShownCut 4
  "spacetime\\.x{50,60}\\.\\.\\.: unknown field; known fields: mass, spin, charge$"
  trace "${generated}/long-key.json" -o out)
asrt_hostile_input_test(Json.LongTypeShownCut 4
  "objects\\[0\\]\\.type: unknown object type \"x{50,60}\\.\\.\\.\" \\(known: celestialSphere"
  trace "${generated}/long-type.json" -o out)

# Scene files without end: read up to the cap and refused, instead of read into all memory.
asrt_hostile_input_test(SceneSize.DevZero 4
  "scene file \"/dev/zero\" is larger than 64 MiB \\(67108864 bytes\\)"
  trace /dev/zero -o out)
asrt_hostile_input_test(SceneSize.EndlessPipe 4
  "scene file \"/dev/stdin\" is larger than 64 MiB"
  SETUP "exec < <(yes '{')"
  trace /dev/stdin -o out)

# Counts the user gives that would allocate up front: usage errors naming the cap.
asrt_hostile_input_test(Series.SweepCap 2 "--sweep: at most 10000 frames in a series, got 1000000000"
  trace "${scenes}/fig1-cylinders.json" --sweep mass=0.1:1:1000000000 -r 8x8 -o out)
asrt_hostile_input_test(Series.OrbitCap 2 "--orbit: at most 10000 frames in a series, got 1000000000"
  trace "${scenes}/fig1-cylinders.json" --orbit 1000000000 -r 8x8 -o out)
asrt_hostile_input_test(Series.OrbitJustAboveCap 2 "--orbit: at most 10000 frames in a series, got 10001"
  trace "${scenes}/fig1-cylinders.json" --orbit 10001:90 -r 8x8 -o out)
asrt_hostile_input_test(Resolution.TraceCap 2
  "--resolution: 100000x100000 is more than the 268435456 pixels \\(2\\^28\\) allowed"
  trace "${scenes}/fig1-cylinders.json" -r 100000x100000 -o out)
asrt_hostile_input_test(Resolution.BundleCap 2
  "--resolution: 1000000000x1000000000 is more than the 268435456 pixels"
  bundle "${scenes}/fig1-cylinders.json" -r 1000000000x1000000000 -o out.png)
asrt_hostile_input_test(Resolution.BundlePictureSide 2 "--size: at most 8192 pixels a side, got 9000x100"
  bundle "${scenes}/fig1-cylinders.json" -r 9x9 --size 9000x100 -o out.png)
asrt_hostile_input_test(Resolution.BundlePictureCap 2
  "--size: 100000x100000 is more than the 268435456 pixels"
  bundle "${scenes}/fig1-cylinders.json" -r 9x9 --size 100000x100000 -o out.png)
asrt_hostile_input_test(Resolution.BenchCap 2
  "--resolution: at most 4194304 pixels \\(2048x2048\\) for a benchmark, got 4096x4096"
  bench -r 4096x4096 -q)
# Polylines keep every step's point: their count is bounded (stride 1 on 400 x 400 is 160000 rays).
asrt_hostile_input_test(Polylines.TraceCap 4
  "160000 rays asked for as polylines; at most 100000 are drawn \\(choose a larger stride"
  trace "${scenes}/fig2-no-hole.json" -r 400x400 --polylines=1 -o out)
asrt_hostile_input_test(Polylines.BundleGridCap 4 "at most 100000 are drawn"
  bundle "${scenes}/fig2-no-hole.json" -r 400x400 --rays grid --step 1 -o out.png)

# Numbers that do not survive parsing: strtod's ERANGE (1e-400 would read as 0, flat space) is a
# usage error naming the option, in the scene file an error naming the field.
asrt_hostile_input_test(Numbers.UnderflowingMass 2
  "--mass: '1e-400' is out of a double's range \\(it would read as 0\\)"
  trace "${scenes}/fig1-cylinders.json" --mass 1e-400 -r 8x8 -o out)
asrt_hostile_input_test(Numbers.UnderflowingMassInTheScene 4
  "spacetime.mass: a number too small for a double"
  SETUP "sed 's/\"mass\": 1,/\"mass\": 1e-400,/' '${scenes}/fig1-cylinders.json' > s.json"
  trace s.json -r 8x8 -o out)
asrt_hostile_input_test(Numbers.CaptureMarginBeyondTheHorizon 4
  "tracing.horizonEpsilon: must lie in \\(0, 1\\]"
  SETUP "sed -e 's/\"horizonEpsilon\": 0.001/\"horizonEpsilon\": 1e300/' -e 's|\\.\\./textures|${scenes}/../textures|' '${scenes}/fig1-cylinders.json' > s.json"
  trace s.json -r 8x8 -o out)
# A series is checked whole before its first frame: an orbit sent to infinity writes nothing.
add_test(NAME CLI.Hostile.Inputs.Series.OrbitToInfinityWritesNothing
  COMMAND ${run_and_check} "${work}/Hostile.Inputs.OrbitToInfinity" ${check}
    "!out-000.png" "!out-001.png" "!out-000.vti" "!out.pvd" --
    ${expect} 4 "orbit inf deg: camera.position: must be finite" --
      ${asrt} trace "${scenes}/kerr-disk.json" --orbit 3:1e308 -r 8x8 -o out)
add_test(NAME CLI.Hostile.Inputs.Series.SpinSweptPastTheMassWritesNothing
  COMMAND ${run_and_check} "${work}/Hostile.Inputs.SpinPastTheMass" ${check}
    "!out-000.png" "!out-001.png" "!out.pvd" --
    ${expect} 4 "spin = 1.5: spacetime: spin \\|a\\| = 1.5 exceeds the mass M = 1" --
      ${asrt} trace "${scenes}/kerr-disk.json" --sweep spin=0.5:1.5:3 -r 8x8 -o out)
set_tests_properties(CLI.Hostile.Inputs.Series.OrbitToInfinityWritesNothing
  CLI.Hostile.Inputs.Series.SpinSweptPastTheMassWritesNothing PROPERTIES LABELS cli TIMEOUT 120)
# Which pixel subset a frame holds is the program's to say: a scene file claiming 3 pixels would
# be traced whole and stored as that subset.
asrt_hostile_input_test(Scene.HandWrittenSubset 4 "subset: is written by the program"
  SETUP "sed -e '1s/^{/{\"subset\": {\"pixels\": 3, \"digest\": \"0123456789abcdef\"},/' -e 's|\\.\\./textures|${scenes}/../textures|' '${scenes}/fig2-no-hole.json' > s.json"
  trace s.json -r 8x8 -o out)
# A scene of 100000 coincident spheres (10 MB), five times the bound, is refused before any
# object is built.
asrt_hostile_input_test(Scene.HundredThousandObjects 4
  "objects: holds 100000 objects; a scene may have at most 20000"
  SETUP "python3 -c \"import json; print(json.dumps({'spacetime': {'mass': 1}, 'camera': {'position': [0, -30, 8], 'focalPoint': [0, 0, 0], 'resolution': [32, 32]}, 'objects': [{'type': 'sphere', 'id': k + 1, 'center': [0, 20, 0], 'radius': 0.5, 'texture': {'color': [1, 1, 1]}} for k in range(100000)]}))\" > s.json"
  trace s.json -o out)
