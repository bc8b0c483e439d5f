# What makes an installed ASRT usable by another CMake project, and the Debian package of it.
# vtk_module_build installs the libraries, headers, ASRT-targets.cmake and
# ASRT-vtk-module-properties.cmake; this adds the ASRTConfig.cmake and ASRTConfigVersion.cmake that
# find_package(ASRT) reads, next to them, and `cpack -G DEB`.
include(CMakePackageConfigHelpers)

set(asrt_package_destination "${CMAKE_INSTALL_LIBDIR}/cmake/asrt")

# The VTK components that the modules' exported interfaces name (for static libraries also their
# private ones, which reach the final link as $<LINK_ONLY:...>), and the module names.
set(ASRT_PACKAGE_VTK_COMPONENTS)
set(ASRT_PACKAGE_MODULE_NAMES)
foreach (asrt_module IN LISTS asrt_modules)
  string(REGEX REPLACE "^ASRT::" "" asrt_module_name "${asrt_module}")
  list(APPEND ASRT_PACKAGE_MODULE_NAMES "${asrt_module_name}")
  get_target_property(asrt_module_interface "${asrt_module}" INTERFACE_LINK_LIBRARIES)
  string(REGEX MATCHALL "VTK::[A-Za-z0-9_]+" asrt_module_vtk "${asrt_module_interface}")
  string(REPLACE "VTK::" "" asrt_module_vtk "${asrt_module_vtk}")
  list(APPEND ASRT_PACKAGE_VTK_COMPONENTS ${asrt_module_vtk})
endforeach ()
list(REMOVE_DUPLICATES ASRT_PACKAGE_VTK_COMPONENTS)
list(JOIN ASRT_PACKAGE_VTK_COMPONENTS " " ASRT_PACKAGE_VTK_COMPONENTS)
list(JOIN ASRT_PACKAGE_MODULE_NAMES " " ASRT_PACKAGE_MODULE_NAMES)
if (BUILD_SHARED_LIBS)
  set(ASRT_PACKAGE_STATIC FALSE)
else ()
  set(ASRT_PACKAGE_STATIC TRUE)
endif ()

configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/ASRTConfig.cmake.in"
  "${CMAKE_BINARY_DIR}/${asrt_package_destination}/ASRTConfig.cmake"
  INSTALL_DESTINATION "${asrt_package_destination}")
# 0.x.y: a project built against 0.1 accepts any 0.z; the major version says what breaks.
write_basic_package_version_file(
  "${CMAKE_BINARY_DIR}/${asrt_package_destination}/ASRTConfigVersion.cmake"
  VERSION "${PROJECT_VERSION}" COMPATIBILITY SameMajorVersion)
install(FILES
  "${CMAKE_BINARY_DIR}/${asrt_package_destination}/ASRTConfig.cmake"
  "${CMAKE_BINARY_DIR}/${asrt_package_destination}/ASRTConfigVersion.cmake"
  DESTINATION "${asrt_package_destination}")

# cpack -G DEB (in the build directory): one package "asrt" with the program, the libraries, the
# headers and CMake files, the Python package and the data, installed under /usr.
set(CPACK_PACKAGE_NAME asrt)
set(CPACK_PACKAGE_VENDOR "ASRT")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "Light near black holes, traced: spacetimes, a ray tracer and VTK filters")
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "ASRT maintainers <maintainers@asrt.invalid>"
  CACHE STRING "The Maintainer field of the Debian package")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# The run-time Depends come from the binaries' NEEDED libraries (dpkg-shlibdeps); building
# against ASRT and its Python package need what the binaries do not say.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The Recommends name the VTK that the build used: ParaView's (paraview-dev, python3-paraview) or
# Debian's own 9.1 (libvtk9-dev, python3-vtk9), whose Python packages conflict.
if (ASRT_HAVE_PARAVIEW)
  set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "paraview-dev, libeigen3-dev, python3-paraview, postgresql")
else ()
  set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libvtk9-dev, libeigen3-dev, python3-vtk9, postgresql")
endif ()
include(CPack)
