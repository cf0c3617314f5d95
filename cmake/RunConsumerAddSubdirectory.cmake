# ctest consumer.add_subdirectory: build and run a project that pulls knnocc in
# with add_subdirectory(); its CMakeLists asserts that knnocc's tests, examples
# and benchmarks stay OFF when knnocc is not the top-level project.
#
# Extra -D variables: KNNOCC_ROOT (knnocc source dir).
include("${CMAKE_CURRENT_LIST_DIR}/ConsumerTestCommon.cmake")

if(NOT KNNOCC_ROOT)
  message(FATAL_ERROR "consumer test: -DKNNOCC_ROOT=... is required")
endif()

knnocc_configure_and_build("-DKNNOCC_ROOT=${KNNOCC_ROOT}")
knnocc_run_app()

message(STATUS "consumer.add_subdirectory: OK")
