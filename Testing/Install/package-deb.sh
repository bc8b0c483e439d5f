#!/usr/bin/env bash
# `cpack -G DEB` packages the build: a package "asrt" whose Depends were found, holding under /usr
# what an install holds (the program, libraries, headers, CMake package, data).
# Usage: package-deb.sh CPACK BUILD_DIR WORK_DIR
#   WORK_DIR is emptied and the package is written there. ASRT_INSTALL_*DIR as for
#   install-and-consume.sh.
set -euo pipefail
cpack=$1 build=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)
source "$here/install-common.sh"

rm -rf "$work"
mkdir -p "$work"
run "$work/cpack.log" "$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$work"
packages=("$work"/*.deb)
if [ "${#packages[@]}" != 1 ] || [ ! -f "${packages[0]}" ]; then
  fail "expected one .deb in $work"
fi
deb=${packages[0]}

[ "$(dpkg-deb -f "$deb" Package)" = asrt ] || fail "$deb is not the package asrt"
depends=$(dpkg-deb -f "$deb" Depends)
echo "Depends: $depends"
# The package that holds the VTK library the build linked (libvtk9.1 for Debian's VTK, paraview
# for ParaView's), as dpkg knows it.
vtk_library=$(readelf -d "$build/${ASRT_INSTALL_LIBDIR}/libasrtFilters.so" |
  sed -n 's/.*Shared library: \[\(libvtkCommonCore[^]]*\)\].*/\1/p')
[ -n "$vtk_library" ] || fail "libasrtFilters.so does not name VTK's CommonCore"
vtk_package=$(dpkg -S "$vtk_library" | sed -n '1s/:.*//p')
[ -n "$vtk_package" ] || fail "no package holds $vtk_library"
grep -E "(^|, )$vtk_package( |,|$)" <<< "$depends" > /dev/null ||
  fail "the Depends do not name $vtk_package, which holds $vtk_library"

# The archive's paths, as ./usr/... (a symbolic link's name without its target).
dpkg-deb -c "$deb" | awk '{ print $6 }' > "$work/contents.txt"
missing=0
for file in $(installed_files); do
  if ! grep -x -F "./usr/$file" "$work/contents.txt" > /dev/null; then
    echo "missing from the package: /usr/$file" >&2
    missing=1
  fi
done
[ "$missing" = 0 ] || fail "files missing from $deb"
echo "$(basename "$deb"): $(wc -l < "$work/contents.txt") entries, OK"
