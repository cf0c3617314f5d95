# Writes a C++ header holding a JavaScript file as raw string pieces of < 64 KB each (ISO C++
# compilers need not accept longer literals): knnocc view pages embed three.js so they open
# without a network. three.js is MIT-licensed ("Expat"): its copyright and permission notice go
# with every copy, so the header also holds that notice (kThreeJsNotice), taken from `license`:
# Debian's copyright file of libjs-three (the "Files: *" copyright line and the Expat text are
# extracted) or a plain licence file such as three.js's own LICENSE (used as it is).
# Called at configure time: knnocc_embed_three_js(<js file> <license file> <header>).
function(knnocc_three_js_notice license out_var)
  file(READ "${license}" _text)
  if(NOT _text MATCHES "Format: https://www.debian.org/doc/packaging-manuals/copyright-format")
    set(${out_var} "${_text}" PARENT_SCOPE)
    return()
  endif()
  # Debian copyright format: "Files: *" names the copyright and the licence of three.js itself;
  # a stand-alone "License: <name>" paragraph holds the text (" ." lines are empty lines).
  if(NOT _text MATCHES "\nFiles: \\*\nCopyright: ([^\n]*)\nLicense: ([^\n]*)\n")
    message(FATAL_ERROR "${license}: no 'Files: *' paragraph with Copyright and License lines")
  endif()
  set(_copyright "${CMAKE_MATCH_1}")
  set(_license "${CMAKE_MATCH_2}")
  string(FIND "${_text}" "\nLicense: ${_license}\n " _at)
  if(_at LESS 0)
    message(FATAL_ERROR "${license}: no text for the licence '${_license}'")
  endif()
  string(SUBSTRING "${_text}" ${_at} -1 _rest)
  string(REGEX MATCH "\nLicense: [^\n]*\n(( [^\n]*\n?)+)" _ "${_rest}")
  string(REGEX REPLACE "(^|\n) \\.(\n|$)" "\\1\\2" _body "${CMAKE_MATCH_1}")
  string(REGEX REPLACE "(^|\n) " "\\1" _body "${_body}")
  set(${out_var}
      "three.js (https://threejs.org), licence ${_license} (MIT)\nCopyright ${_copyright}\n\n${_body}"
      PARENT_SCOPE)
endfunction()

function(knnocc_embed_three_js js license header)
  knnocc_three_js_notice("${license}" _notice)
  if(_notice MATCHES "\\*/|\\)knnoccjs\"")
    message(FATAL_ERROR "${license}: the notice cannot be embedded (it contains */ or )knnoccjs\")")
  endif()
  file(READ "${js}" _text)
  string(LENGTH "${_text}" _len)
  set(_out "// Generated from ${js} and ${license} by cmake/EmbedThreeJs.cmake; do not edit.\n#pragma once\n#include <cstddef>\nnamespace knnocc::cli::detail {\ninline const char* const kThreeJsPieces[] = {\n")
  set(_pos 0)
  while(_pos LESS _len)
    string(SUBSTRING "${_text}" ${_pos} 60000 _piece)
    string(APPEND _out "R\"knnoccjs(${_piece})knnoccjs\",\n")
    math(EXPR _pos "${_pos} + 60000")
  endwhile()
  string(APPEND _out "};\ninline constexpr std::size_t kThreeJsBytes = ${_len};\n")
  string(APPEND _out "/// three.js's copyright and permission notice, to go with every embedded copy.\n")
  string(APPEND _out "inline constexpr const char* kThreeJsNotice = R\"knnoccjs(${_notice})knnoccjs\";\n")
  string(APPEND _out "}  // namespace knnocc::cli::detail\n")
  file(WRITE "${header}.tmp" "${_out}")
  execute_process(COMMAND "${CMAKE_COMMAND}" -E copy_if_different "${header}.tmp" "${header}")
  file(REMOVE "${header}.tmp")
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${js}" "${license}")
endfunction()
