# ctest style.concept_checks and style.public_surface: each DIR/*.cpp must fail to compile with
# the message its first line names ("// expect: REGEX"). tests/concept_checks/ break one of
# Mapper's concepts (sensor model, tracker, scan integrator): a static_assert must say what is
# missing. tests/public_surface/ call a member users must not reach (the map's brick writers,
# the tracker's marks): the compiler must refuse the access.
#
# -D variables: CXX (compiler), ROOT (project root), DIR (tests/concept_checks or
# tests/public_surface), STATIC_ASSERT (ON: the message must come from a static_assert), INCLUDES
# (optional further -I flags separated by '|').
file(GLOB _sources "${ROOT}/${DIR}/*.cpp")
if(NOT _sources)
  message(FATAL_ERROR "no sources in ${ROOT}/${DIR}")
endif()
string(REPLACE "|" ";" _includes "${_includes}")  # further -I flags, '|'-separated
foreach(_source IN LISTS _sources)
  file(STRINGS "${_source}" _first LIMIT_COUNT 1)
  if(NOT _first MATCHES "^// expect: (.+)$")
    message(FATAL_ERROR "${_source}: the first line must be // expect: REGEX")
  endif()
  set(_expect "${CMAKE_MATCH_1}")
  execute_process(COMMAND "${CXX}" -std=c++17 -fsyntax-only "-I${ROOT}/include" ${_includes}
                          "${_source}"
                  RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _out)
  get_filename_component(_name "${_source}" NAME)
  if(_rc EQUAL 0)
    message(FATAL_ERROR "${_name} compiled, but it must be refused")
  endif()
  if(STATIC_ASSERT AND NOT _out MATCHES "static assert[^\n]*${_expect}")
    message(FATAL_ERROR "${_name}: no static_assert saying '${_expect}' in:\n${_out}")
  elseif(NOT _out MATCHES "${_expect}")
    message(FATAL_ERROR "${_name}: no error saying '${_expect}' in:\n${_out}")
  endif()
  message(STATUS "${_name}: refused with the expected message")
endforeach()
