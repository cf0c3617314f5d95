# ctest consumer.find_package: install knnocc into a scratch prefix, then build
# and run a project that uses find_package(knnocc) + knnocc::knnocc, and check
# the installed pkg-config file.
#
# Extra -D variables: KNNOCC_BUILD_DIR, INSTALL_CMAKEDIR, INSTALL_PKGCONFIGDIR,
# INSTALL_INCLUDEDIR (as configured, usually relative to the prefix),
# PKG_CONFIG_EXECUTABLE (optional).
include("${CMAKE_CURRENT_LIST_DIR}/ConsumerTestCommon.cmake")

set(prefix "${WORK_DIR}/prefix")

# Resolve an install dir the way CMake does: relative dirs are under prefix.
function(knnocc_in_prefix out dir)
  if(IS_ABSOLUTE "${dir}")
    set(${out} "${dir}" PARENT_SCOPE)
  else()
    set(${out} "${prefix}/${dir}" PARENT_SCOPE)
  endif()
endfunction()

# 1. Install. Header-only: no build is needed for this to work.
message(STATUS "Installing ${KNNOCC_BUILD_DIR} into ${prefix}")
set(_install "${CMAKE_COMMAND}" --install "${KNNOCC_BUILD_DIR}" --prefix "${prefix}")
if(CONFIG)
  list(APPEND _install --config "${CONFIG}")
endif()
knnocc_run(${_install})

knnocc_in_prefix(cmakedir "${INSTALL_CMAKEDIR}")
knnocc_in_prefix(pcdir "${INSTALL_PKGCONFIGDIR}")
knnocc_in_prefix(incdir "${INSTALL_INCLUDEDIR}")
foreach(_f
    "${cmakedir}/knnoccConfig.cmake"
    "${cmakedir}/knnoccConfigVersion.cmake"
    "${cmakedir}/knnocc-core-targets.cmake"
    "${cmakedir}/knnocc-knn-targets.cmake"
    "${cmakedir}/knnocc-io-targets.cmake"
    "${cmakedir}/knnocc-knnocc-targets.cmake"
    "${pcdir}/knnocc.pc"
    "${incdir}/knnocc/version.hpp"
    "${incdir}/knnocc/knnocc.hpp")
  if(NOT EXISTS "${_f}")
    message(FATAL_ERROR "Expected installed file missing: ${_f}")
  endif()
endforeach()

# 2. Configure/build/run the consumer against the scratch prefix only (no
#    package registry, so a stale registration cannot satisfy find_package).
knnocc_configure_and_build(
  "-DCMAKE_PREFIX_PATH=${prefix}"
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)

# Make sure it really used the freshly installed package.
file(STRINGS "${WORK_DIR}/build/CMakeCache.txt" _dir_line REGEX "^knnocc_DIR:")
string(REGEX REPLACE "^knnocc_DIR:[A-Z]+=" "" _found_dir "${_dir_line}")
get_filename_component(_found_dir "${_found_dir}" REALPATH)
get_filename_component(_want_dir "${cmakedir}" REALPATH)
if(NOT _found_dir STREQUAL _want_dir)
  message(FATAL_ERROR "find_package(knnocc) used '${_found_dir}', expected '${_want_dir}'")
endif()

knnocc_run_app()

# 3. pkg-config (optional tool): Cflags must point at the installed headers.
if(PKG_CONFIG_EXECUTABLE AND EXISTS "${PKG_CONFIG_EXECUTABLE}")
  set(ENV{PKG_CONFIG_PATH} "${pcdir}")
  knnocc_run("${PKG_CONFIG_EXECUTABLE}" --modversion knnocc)
  string(STRIP "${KNNOCC_RUN_OUTPUT}" _pc_version)
  if(NOT _pc_version STREQUAL EXPECTED_VERSION)
    message(FATAL_ERROR "pkg-config --modversion knnocc: '${_pc_version}', expected '${EXPECTED_VERSION}'")
  endif()
  knnocc_run("${PKG_CONFIG_EXECUTABLE}" --cflags knnocc)
  set(_cflags "${KNNOCC_RUN_OUTPUT}")
  message(STATUS "pkg-config --cflags knnocc: ${_cflags}")
  # Compare normalised paths (the prefix may be reached through a symlink).
  get_filename_component(_want_inc "${incdir}" REALPATH)
  separate_arguments(_flags UNIX_COMMAND "${_cflags}")
  set(_ok FALSE)
  foreach(_flag IN LISTS _flags)
    if(_flag MATCHES "^-I(.+)$")
      get_filename_component(_inc "${CMAKE_MATCH_1}" REALPATH)
      if(_inc STREQUAL _want_inc)
        set(_ok TRUE)
      endif()
    endif()
  endforeach()
  if(NOT _ok)
    message(FATAL_ERROR "pkg-config --cflags knnocc does not contain -I${incdir}: ${_cflags}")
  endif()
else()
  message(STATUS "pkg-config not available; skipping the knnocc.pc check")
endif()

message(STATUS "consumer.find_package: OK")
