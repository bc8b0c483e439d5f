#!/usr/bin/env bash
# An installed ASRT works on its own. `cmake --install` puts the build into a scratch prefix, then:
#  - the installed program traces an installed scene, loads the installed libraries through its
#    RUNPATH (no LD_LIBRARY_PATH) and finds the installed data from its own path;
#  - the installed Python package imports (when the build wraps Python);
#  - the installed ParaView plugin loads in pvpython (when the build makes it);
#  - a project outside ASRT's tree (downstream/) finds ASRT with find_package(ASRT), links
#    ASRT::Filters to trace a scene into a PNG, and ASRT::Physics alone, without libpq, to check a
#    fact of the Schwarzschild spacetime.
# Usage: install-and-consume.sh CMAKE BUILD_DIR WORK_DIR CHECKER
#   WORK_DIR is emptied and everything is written there; CHECKER is asrtCheckOutputs. The install
#   directories (relative to the prefix) come from the environment: ASRT_INSTALL_BINDIR, _LIBDIR,
#   _HEADERDIR, _DATADIR, ASRT_INSTALL_PYTHONDIR (empty without the Python package) and
#   ASRT_INSTALL_PLUGINDIR with ASRT_PVPYTHON (empty without the ParaView plugin).
set -euo pipefail
cmake=$1 build=$2 work=$3 checker=$4
here=$(cd "$(dirname "$0")" && pwd)
source "$here/install-common.sh"
unset LD_LIBRARY_PATH ASRT_DATA_DIR PYTHONPATH

rm -rf "$work"
mkdir -p "$work/out"
# The physical path: the program sees its own location with symbolic links resolved.
work=$(cd "$work" && pwd -P)
prefix=$work/prefix
run "$work/install.log" "$cmake" --install "$build" --prefix "$prefix"

# What the install holds: the program, one library and the headers of each module, the CMake
# package and the data.
expect_files "$prefix" "$(installed_files)"

# The installed program on its own: its libraries, its data, a traced frame.
asrt=$prefix/$ASRT_INSTALL_BINDIR/asrt
readelf -d "$asrt" | grep -E '(RUNPATH|RPATH).*\$ORIGIN' > /dev/null ||
  fail "$asrt has no \$ORIGIN-relative RUNPATH"
# The launcher loads the program's library (libasrtProgram) through that RUNPATH, and the library
# the ASRT libraries through its own.
program=$prefix/$ASRT_INSTALL_LIBDIR/libasrtProgram.so
[ -f "$program" ] || fail "$program is not installed"
readelf -d "$program" | grep -E '(RUNPATH|RPATH).*\$ORIGIN' > /dev/null ||
  fail "$program has no \$ORIGIN-relative RUNPATH"
ldd "$program" > "$work/asrt.ldd"
if grep libasrt "$work/asrt.ldd" | grep -v -F "=> $prefix/" > /dev/null; then
  cat "$work/asrt.ldd"
  fail "$program loads ASRT libraries from outside the prefix"
fi
scene=$prefix/$ASRT_INSTALL_DATADIR/asrt/scenes/fig1-cylinders.json
run "$work/trace.log" "$asrt" trace "$scene" -r 32x32 -q --formats png -o "$work/out/installed-asrt"
"$checker" "$work/out/installed-asrt.png=32x32"
# asrt bench traces the preset scene from the data directory and names the file it read.
run "$work/bench.log" "$asrt" bench -r 4x4 --repeat 1 -q
grep -F "asrt bench: $scene " "$work/bench.log" > /dev/null ||
  fail "the installed asrt did not read the installed scenes: $(head -1 "$work/bench.log")"

if [ -n "${ASRT_INSTALL_PYTHONDIR:-}" ]; then
  PYTHONPATH=$prefix/$ASRT_INSTALL_PYTHONDIR run "$work/python.log" "${ASRT_PYTHON:-python3}" -c "
import asrt
assert asrt.__file__.startswith('$prefix/'), asrt.__file__
source = asrt.vtkGeodesicSource()
print(source.GetClassName())"
  grep -x vtkGeodesicSource "$work/python.log" > /dev/null || fail "the Python package did not load"
fi

# The installed ParaView plugin loads in pvpython from the prefix, its libraries through its
# RUNPATH, and traces a frame.
if [ -n "${ASRT_INSTALL_PLUGINDIR:-}" ]; then
  plugin=$prefix/$ASRT_INSTALL_PLUGINDIR/ASRT.so
  ldd "$plugin" > "$work/plugin.ldd"
  if grep libasrt "$work/plugin.ldd" | grep -v -F "=> $prefix/" > /dev/null; then
    cat "$work/plugin.ldd"
    fail "$plugin loads ASRT libraries from outside the prefix"
  fi
  run "$work/plugin.log" "$ASRT_PVPYTHON" -c "
from paraview.simple import LoadPlugin
from paraview import servermanager
LoadPlugin('$plugin', remote=False, ns=globals())
source = ASRTGeodesicSource(SceneFileName='$scene', Resolution=[8, 6])
print('plugin image points', servermanager.Fetch(source, idx=0).GetNumberOfPoints())"
  grep -x "plugin image points 48" "$work/plugin.log" > /dev/null ||
    fail "the installed plugin did not trace: $(tail -3 "$work/plugin.log")"
fi

# A downstream project, against this prefix only (no package registry).
downstream=$work/downstream
run "$work/downstream-configure.log" "$cmake" -S "$here/downstream" -B "$downstream" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF
grep -x "ASRT_DIR:PATH=$prefix/$ASRT_INSTALL_LIBDIR/cmake/asrt" "$downstream/CMakeCache.txt" \
  > /dev/null || fail "find_package(ASRT) did not find the installed package: $(grep ASRT_DIR "$downstream/CMakeCache.txt")"
run "$work/downstream-build.log" "$cmake" --build "$downstream" -j 2

run "$work/downstream-trace.log" "$downstream/downstream_trace" "$scene" \
  "$work/out/downstream.png" 32 32
"$checker" "$work/out/downstream.png=32x32"

run "$work/downstream-physics.log" "$downstream/downstream_physics"
cat "$work/downstream-physics.log"
# Physics alone needs no PostgreSQL client, neither directly nor through a library it loads, and
# none of the modules above it; the traced program, which links ASRT::Store through
# ASRT::Filters, does (so the check can see it).
readelf -d "$downstream/downstream_physics" | grep NEEDED | grep libpq &&
  fail "downstream_physics needs libpq"
ldd "$downstream/downstream_physics" > "$work/downstream_physics.ldd"
grep -E 'libpq|libasrt(Tracing|Store|Interpolation|Filters)' "$work/downstream_physics.ldd" &&
  fail "downstream_physics loads libpq or a module above ASRT::Physics"
ldd "$downstream/downstream_trace" | grep libpq > /dev/null ||
  fail "downstream_trace does not load libpq: the check above would not see it"
echo "install and downstream project: OK"
