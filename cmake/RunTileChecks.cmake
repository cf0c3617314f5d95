# Maps one input with every model in one process and into tiles, and checks that the tile set
# merges into the one-process .bt and .ot byte for byte (map -o, map --out-tiles -o, and merge).
#   -DTOOL=<path>        the knnocc executable
#   -DINPUT=<path>       a sequence folder or a point file
#   -DRES=<r>            --res
#   -DDEPTHS=a|b|c       tile depths; RANDOM in the list is replaced by a depth drawn from 1..13
#   -DMODELS=a|b         models (default octomap|knn|knn2022|robust)
#   -DEXTRA=a|b          more map arguments (e.g. --crop|4)
#   -DOUT=<dir>          scratch folder (removed first)
cmake_minimum_required(VERSION 3.16)
if(NOT DEFINED MODELS)
  set(MODELS "octomap|knn|knn2022|robust")
endif()
string(REPLACE "|" ";" _models "${MODELS}")
string(REPLACE "|" ";" _depths "${DEPTHS}")
string(REPLACE "|" ";" _extra "${EXTRA}")
string(RANDOM LENGTH 2 ALPHABET "0123456789" _r)
math(EXPR _random "${_r} % 13 + 1")
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")

include("${CMAKE_CURRENT_LIST_DIR}/RunToolCommon.cmake")

function(same a b what)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${a}" "${b}" RESULT_VARIABLE _d)
  if(NOT _d EQUAL 0)
    message(FATAL_ERROR "${what}: ${a} and ${b} differ")
  endif()
endfunction()

set(_checked 0)
foreach(_model IN LISTS _models)
  run_tool(map --input "${INPUT}" --res ${RES} --model ${_model} ${_extra}
           -o "${OUT}/${_model}.bt" -o "${OUT}/${_model}.ot")
  foreach(_depth IN LISTS _depths)
    if(_depth STREQUAL "RANDOM")
      set(_depth ${_random})
    endif()
    set(_tiles "${OUT}/${_model}_tiles_${_depth}")
    run_tool(map --input "${INPUT}" --res ${RES} --model ${_model} ${_extra}
             --out-tiles "${_tiles}" --tile-depth ${_depth} -o "${OUT}/${_model}_${_depth}.bt")
    if(NOT _stdout MATCHES "tiles [0-9]+ depth ${_depth} edge_m [0-9.e+-]+ key_bits 16\nclouds")
      message(FATAL_ERROR "map --out-tiles printed no tiles line:\n${_stdout}")
    endif()
    same("${OUT}/${_model}.bt" "${OUT}/${_model}_${_depth}.bt" "${_model} at tile depth ${_depth}")
    run_tool(merge "${_tiles}" -o "${OUT}/${_model}_${_depth}.ot")
    same("${OUT}/${_model}.ot" "${OUT}/${_model}_${_depth}.ot" "${_model} at tile depth ${_depth}")
    file(REMOVE_RECURSE "${_tiles}")
    math(EXPR _checked "${_checked} + 1")
  endforeach()
endforeach()
message(STATUS "${_checked} tile sets merged into the one-process .bt and .ot (random depth ${_random})")
file(REMOVE_RECURSE "${OUT}")
