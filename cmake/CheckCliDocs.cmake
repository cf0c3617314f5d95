# Fails when docs/cli.md is not what the tool prints with `knnocc help --markdown`.
#   -DTOOL=<knnocc> -DDOC=<docs/cli.md> -DOUT=<scratch file>
execute_process(COMMAND "${TOOL}" help --markdown OUTPUT_FILE "${OUT}" RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "knnocc help --markdown failed (exit ${_rc})")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${DOC}" "${OUT}" RESULT_VARIABLE _same)
if(NOT _same EQUAL 0)
  message(FATAL_ERROR "docs/cli.md is stale: it differs from `knnocc help --markdown` (${OUT}); "
                      "regenerate it with: cmake --build build --target cli_docs")
endif()
