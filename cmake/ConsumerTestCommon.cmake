# Helpers shared by the consumer.* ctest scripts (included in cmake -P mode).
#
# Expected -D variables (set by tests/CMakeLists.txt):
#   WORK_DIR           scratch directory, wiped at the start of each run
#   CONSUMER_SOURCE    source dir of the tiny consumer project
#   CONSUMER_GENERATOR / CONSUMER_MAKE_PROGRAM / CONSUMER_CXX_COMPILER / CONFIG
#   EXPECTED_VERSION   knnocc version the app must print

foreach(_var WORK_DIR CONSUMER_SOURCE CONSUMER_GENERATOR CONSUMER_CXX_COMPILER EXPECTED_VERSION)
  if(NOT DEFINED ${_var} OR "${${_var}}" STREQUAL "")
    message(FATAL_ERROR "consumer test: -D${_var}=... is required")
  endif()
endforeach()

# Run a command, echo it, and abort the test with its output if it fails.
function(knnocc_run)
  execute_process(COMMAND ${ARGN}
    RESULT_VARIABLE _rc
    OUTPUT_VARIABLE _out
    ERROR_VARIABLE _out)
  if(NOT _rc EQUAL 0)
    string(REPLACE ";" " " _cmd "${ARGN}")
    message(FATAL_ERROR "Command failed (${_rc}): ${_cmd}\n${_out}")
  endif()
  set(KNNOCC_RUN_OUTPUT "${_out}" PARENT_SCOPE)
endfunction()

# Configure + build the consumer project into WORK_DIR/build, extra args are
# passed to the configure step.
function(knnocc_configure_and_build)
  set(_args
    -S "${CONSUMER_SOURCE}" -B "${WORK_DIR}/build"
    -G "${CONSUMER_GENERATOR}"
    "-DCMAKE_CXX_COMPILER=${CONSUMER_CXX_COMPILER}"
    "-DCMAKE_BUILD_TYPE=${CONFIG}")
  if(CONSUMER_MAKE_PROGRAM)
    list(APPEND _args "-DCMAKE_MAKE_PROGRAM=${CONSUMER_MAKE_PROGRAM}")
  endif()
  message(STATUS "Configuring consumer ${CONSUMER_SOURCE}")
  knnocc_run("${CMAKE_COMMAND}" ${_args} ${ARGN})
  message(STATUS "Building consumer")
  set(_build "${CMAKE_COMMAND}" --build "${WORK_DIR}/build" -j2)
  if(CONFIG)
    list(APPEND _build --config "${CONFIG}")
  endif()
  knnocc_run(${_build})
endfunction()

# Run the consumer's app (placed in WORK_DIR/build/bin by its CMakeLists) and
# check that it exits 0 and prints the expected version.
function(knnocc_run_app)
  set(_app "${WORK_DIR}/build/bin/app")
  if(NOT EXISTS "${_app}" AND EXISTS "${_app}.exe")
    set(_app "${_app}.exe")
  endif()
  if(NOT EXISTS "${_app}")
    message(FATAL_ERROR "consumer app not found at ${_app}")
  endif()
  knnocc_run("${_app}")
  if(NOT KNNOCC_RUN_OUTPUT MATCHES "knnocc ${EXPECTED_VERSION}")
    message(FATAL_ERROR "consumer app printed '${KNNOCC_RUN_OUTPUT}', "
                        "expected 'knnocc ${EXPECTED_VERSION}'")
  endif()
  message(STATUS "App output: ${KNNOCC_RUN_OUTPUT}")
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
