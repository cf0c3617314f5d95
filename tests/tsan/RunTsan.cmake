# Builds tests/tsan (the multithreaded-insertion tests with -fsanitize=thread) in a nested build
# tree and runs them; any ThreadSanitizer report fails the test.
#   -DCXX=<compiler> -DROOT=<project root> -DWORK_DIR=<build dir>
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${ROOT}/tests/tsan" -B "${WORK_DIR}"
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DKNNOCC_ROOT=${ROOT}"
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "configuring the ThreadSanitizer build with ${CXX} failed")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${WORK_DIR}" -j2 RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "building with ${CXX} -fsanitize=thread failed")
endif()
set(ENV{TSAN_OPTIONS} "halt_on_error=1 exitcode=66 second_deadlock_stack=1")
execute_process(COMMAND "${WORK_DIR}/knnocc_tsan_tests" "--test-case=insert_threads.*,concurrent_queries.*"
                        "--test-case-exclude=*scan_dat*"
  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
message("${_out}${_err}")
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "ThreadSanitizer run failed (exit ${_rc})")
endif()
