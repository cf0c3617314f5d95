# ctest consumer.core_find_package / consumer.core_add_subdirectory: knnocc without Eigen and
# nanoflann. find_package: knnocc is configured with both hidden (CMAKE_DISABLE_FIND_PACKAGE_*),
# which must succeed and leave the targets that need them out, and installed into a scratch
# prefix. Then the consumer (tests/consumer/core), with both hidden too, uses knnocc::core alone;
# headers named like theirs stop its build if anything includes them.
#
# Extra -D variables: MODE (find_package or add_subdirectory), KNNOCC_ROOT (knnocc source dir).
include("${CMAKE_CURRENT_LIST_DIR}/ConsumerTestCommon.cmake")

set(_hide -DCMAKE_DISABLE_FIND_PACKAGE_Eigen3=ON -DCMAKE_DISABLE_FIND_PACKAGE_nanoflann=ON)
if(MODE STREQUAL "find_package")
  set(prefix "${WORK_DIR}/prefix")
  set(_args -S "${KNNOCC_ROOT}" -B "${WORK_DIR}/knnocc" -G "${CONSUMER_GENERATOR}"
            "-DCMAKE_CXX_COMPILER=${CONSUMER_CXX_COMPILER}" "-DCMAKE_INSTALL_PREFIX=${prefix}"
            -DKNNOCC_BUILD_TESTS=OFF -DKNNOCC_BUILD_EXAMPLES=OFF -DKNNOCC_BUILD_BENCH=OFF ${_hide})
  if(CONSUMER_MAKE_PROGRAM)
    list(APPEND _args "-DCMAKE_MAKE_PROGRAM=${CONSUMER_MAKE_PROGRAM}")
  endif()
  message(STATUS "Configuring knnocc without Eigen and nanoflann")
  knnocc_run("${CMAKE_COMMAND}" ${_args})
  foreach(_said "knnocc::knn" "knnocc::io")
    if(NOT KNNOCC_RUN_OUTPUT MATCHES "not found: ${_said}")
      message(FATAL_ERROR "configure did not say that ${_said} is left out:\n${KNNOCC_RUN_OUTPUT}")
    endif()
  endforeach()
  knnocc_run("${CMAKE_COMMAND}" --install "${WORK_DIR}/knnocc")
  knnocc_configure_and_build(-DKNNOCC_CONSUMER_MODE=find_package "-DCMAKE_PREFIX_PATH=${prefix}"
                             -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF ${_hide})
else()
  knnocc_configure_and_build(-DKNNOCC_CONSUMER_MODE=add_subdirectory
                             "-DKNNOCC_ROOT=${KNNOCC_ROOT}" ${_hide})
endif()
knnocc_run_app()
message(STATUS "consumer.core_${MODE}: OK")
