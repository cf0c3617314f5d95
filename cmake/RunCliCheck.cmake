# Runs the knnocc tool once and checks what a user would see.
#   -DTOOL=<path>            the knnocc executable
#   -DARGS=a|b|c             its arguments, separated by '|'
#   -DEXPECT_EXIT=<n>        required exit status
#   -DSTDOUT_REGEX=<re>      optional: stdout must match
#   -DSTDERR_REGEX=<re>      optional: stderr must match
#   -DWRITE_FILE=<path> -DWRITE_CONTENT=<text>   optional: input file created first
#   -DEXPECT_FILE=<path>     optional: must exist afterwards (removed first); a|b for several
#   -DNO_FILE=<path>         optional: must not exist afterwards, nor <path>.tmp (removed first)
#   -DSAME_FILES=<a>|<b>     optional: the two files must be byte for byte identical
#   -DCLEAN_DIR=<path>       optional: a folder removed first (outputs that refuse a non-empty one)
string(REPLACE "|" ";" _args "${ARGS}")
string(REPLACE "|" ";" _expect_files "${EXPECT_FILE}")
foreach(_f IN LISTS _expect_files ITEMS "${NO_FILE}")
  if(_f)
    file(REMOVE "${_f}" "${_f}.tmp")
  endif()
endforeach()
if(CLEAN_DIR)
  file(REMOVE_RECURSE "${CLEAN_DIR}")
endif()
if(WRITE_FILE)
  file(WRITE "${WRITE_FILE}" "${WRITE_CONTENT}")
endif()
execute_process(COMMAND "${TOOL}" ${_args}
  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
message(STATUS "exit ${_rc}\nstdout:\n${_out}\nstderr:\n${_err}")
if(NOT "${_rc}" STREQUAL "${EXPECT_EXIT}")
  message(FATAL_ERROR "expected exit status ${EXPECT_EXIT}, got ${_rc}")
endif()
if(DEFINED STDOUT_REGEX AND NOT _out MATCHES "${STDOUT_REGEX}")
  message(FATAL_ERROR "stdout does not match: ${STDOUT_REGEX}")
endif()
if(DEFINED STDERR_REGEX AND NOT _err MATCHES "${STDERR_REGEX}")
  message(FATAL_ERROR "stderr does not match: ${STDERR_REGEX}")
endif()
foreach(_f IN LISTS _expect_files)
  if(NOT EXISTS "${_f}")
    message(FATAL_ERROR "expected output file ${_f} was not written")
  endif()
endforeach()
if(NO_FILE AND (EXISTS "${NO_FILE}" OR EXISTS "${NO_FILE}.tmp"))
  message(FATAL_ERROR "${NO_FILE} (or its temporary) exists after a failed run")
endif()
if(SAME_FILES)
  string(REPLACE "|" ";" _pair "${SAME_FILES}")
  execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files ${_pair} RESULT_VARIABLE _same)
  if(NOT _same EQUAL 0)
    message(FATAL_ERROR "files differ: ${SAME_FILES}")
  endif()
endif()
