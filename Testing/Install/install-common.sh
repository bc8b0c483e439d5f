# shellcheck shell=bash
# Shared by the install tests: running a step quietly, and the files an install must hold.

fail()
{
  echo "FAIL: $*" >&2
  exit 1
}

# run LOG COMMAND...: runs the command with its output in LOG, shown only when it fails.
run()
{
  local log=$1
  shift
  local code=0
  "$@" > "$log" 2>&1 || code=$?
  if [ "$code" != 0 ]; then
    cat "$log" >&2
    fail "$* (exit code $code)"
  fi
}

# The files of an install, relative to its prefix (ASRT_INSTALL_*DIR from the environment): the
# program, each module's shared library and headers (a class header and the export header), the
# CMake package, and the scenes and textures.
installed_files()
{
  local lib=$ASRT_INSTALL_LIBDIR include=$ASRT_INSTALL_HEADERDIR
  echo "$ASRT_INSTALL_BINDIR/asrt"
  local module
  for module in Physics Tracing Store Interpolation Filters; do
    echo "$lib/libasrt$module.so"
    echo "$include/asrt${module}Module.h"
  done
  echo "$include/Spacetime.h $include/SceneFile.h $include/RayStore.h"
  echo "$include/FrameInterpolation.h $include/vtkGeodesicSource.h"
  echo "$lib/cmake/asrt/ASRTConfig.cmake $lib/cmake/asrt/ASRTConfigVersion.cmake"
  echo "$lib/cmake/asrt/ASRT-targets.cmake $lib/cmake/asrt/ASRT-vtk-module-properties.cmake"
  echo "$ASRT_INSTALL_DATADIR/asrt/scenes/fig1-cylinders.json"
  echo "$ASRT_INSTALL_DATADIR/asrt/scenes/kerr-disk.json"
  echo "$ASRT_INSTALL_DATADIR/asrt/textures/galaxy.png"
  echo "$ASRT_INSTALL_DATADIR/asrt/textures/checker.png"
  if [ -n "${ASRT_INSTALL_PLUGINDIR:-}" ]; then
    echo "$ASRT_INSTALL_PLUGINDIR/ASRT.so"
  fi
}

# expect_files ROOT "FILES": each of the files exists under ROOT.
expect_files()
{
  local root=$1 file missing=0
  for file in $2; do
    if [ ! -e "$root/$file" ]; then
      echo "missing: $root/$file" >&2
      missing=1
    fi
  done
  [ "$missing" = 0 ] || fail "files missing under $root"
}
