# Fails when a C++ source differs from .clang-format's layout.
#   -DCLANG_FORMAT=<exe> -DROOT=<project root>
file(GLOB_RECURSE _files
  "${ROOT}/include/*.hpp" "${ROOT}/tests/*.hpp" "${ROOT}/tests/*.cpp"
  "${ROOT}/examples/*.hpp" "${ROOT}/examples/*.cpp" "${ROOT}/bench/*.hpp" "${ROOT}/bench/*.cpp")
execute_process(COMMAND "${CLANG_FORMAT}" --dry-run --Werror ${_files}
  RESULT_VARIABLE _rc ERROR_VARIABLE _err)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "clang-format: these files need `clang-format -i`:\n${_err}")
endif()
list(LENGTH _files _n)
message(STATUS "${_n} files formatted as .clang-format says")
