# Writes a C++ header holding a JavaScript file as raw string pieces of < 64 KB each (ISO C++
# compilers need not accept longer literals): knnocc view pages embed three.js so they open
# without a network. Called at configure time: embed_three_js(<js file> <header>).
function(knnocc_embed_three_js js header)
  file(READ "${js}" _text)
  string(LENGTH "${_text}" _len)
  set(_out "// Generated from ${js} by cmake/EmbedThreeJs.cmake; do not edit.\n#pragma once\n#include <cstddef>\nnamespace knnocc::cli::detail {\ninline const char* const kThreeJsPieces[] = {\n")
  set(_pos 0)
  while(_pos LESS _len)
    string(SUBSTRING "${_text}" ${_pos} 60000 _piece)
    string(APPEND _out "R\"knnoccjs(${_piece})knnoccjs\",\n")
    math(EXPR _pos "${_pos} + 60000")
  endwhile()
  string(APPEND _out "};\ninline constexpr std::size_t kThreeJsBytes = ${_len};\n}  // namespace knnocc::cli::detail\n")
  file(WRITE "${header}.tmp" "${_out}")
  execute_process(COMMAND "${CMAKE_COMMAND}" -E copy_if_different "${header}.tmp" "${header}")
  file(REMOVE "${header}.tmp")
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${js}")
endfunction()
