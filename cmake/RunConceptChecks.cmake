# ctest style.concept_checks: each tests/concept_checks/*.cpp breaks one of Mapper's concepts
# (sensor model, tracker, scan integrator) and must fail to compile with the static_assert
# message its first line names ("// expect: REGEX").
#
# -D variables: CXX (compiler), ROOT (project root).
file(GLOB _sources "${ROOT}/tests/concept_checks/*.cpp")
if(NOT _sources)
  message(FATAL_ERROR "no sources in ${ROOT}/tests/concept_checks")
endif()
foreach(_source IN LISTS _sources)
  file(STRINGS "${_source}" _first LIMIT_COUNT 1)
  if(NOT _first MATCHES "^// expect: (.+)$")
    message(FATAL_ERROR "${_source}: the first line must be // expect: REGEX")
  endif()
  set(_expect "${CMAKE_MATCH_1}")
  execute_process(COMMAND "${CXX}" -std=c++17 -fsyntax-only "-I${ROOT}/include" "${_source}"
                  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  get_filename_component(_name "${_source}" NAME)
  if(_rc EQUAL 0)
    message(FATAL_ERROR "${_name} compiled, but it breaks a concept")
  endif()
  if(NOT _out MATCHES "static assert[^\n]*${_expect}")
    message(FATAL_ERROR "${_name}: no static_assert saying '${_expect}' in:\n${_out}")
  endif()
  message(STATUS "${_name}: refused with the expected message")
endforeach()
