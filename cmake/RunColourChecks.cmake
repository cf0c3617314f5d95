# Colour along every path of the tool that can carry it, read back from what was written; and the
# one note on stderr where a path cannot.
#   -DTOOL=<path>   the knnocc executable
#   -DOUT=<dir>     scratch folder (removed first)
cmake_minimum_required(VERSION 3.16)
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")

include("${CMAKE_CURRENT_LIST_DIR}/RunToolCommon.cmake")

# `text` must hold exactly `n` lines with "note:" and, when n > 0, match `re`.
function(expect_notes text n re what)
  string(REGEX MATCHALL "note:" _notes "${text}")
  list(LENGTH _notes _count)
  if(NOT _count EQUAL n)
    message(FATAL_ERROR "${what}: ${_count} notes on stderr, expected ${n}:\n${text}")
  endif()
  if(n GREATER 0 AND NOT text MATCHES "${re}")
    message(FATAL_ERROR "${what}: stderr does not match ${re}:\n${text}")
  endif()
endfunction()

# The map file's voxel colours, read back as an ascii PLY of its occupied voxels: each colour in
# the list `colours` ("r g b") must be some voxel's.
function(expect_voxel_colours map colours what)
  run_tool(convert "${map}" "${map}.check.ply" --encoding ascii)
  file(READ "${map}.check.ply" _ply)
  foreach(_c IN LISTS colours)
    if(NOT _ply MATCHES "\n[^ \n]+ [^ \n]+ [^ \n]+ ${_c} [^ \n]+\n")
      message(FATAL_ERROR "${what}: no voxel of ${map} has colour ${_c}:\n${_ply}")
    endif()
  endforeach()
endfunction()

function(expect_tree_id file id what)
  file(READ "${file}" _head LIMIT 200)
  if(NOT _head MATCHES "\nid ${id}\n")
    message(FATAL_ERROR "${what}: ${file} is not a ${id}:\n${_head}")
  endif()
endfunction()

# The same three coloured points in every PLY colour type: (200 10 20) and (100 30 40) share a
# voxel at --res 0.1 (mean 150 20 30), (0 0 255) has its own.
set(_head "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n")
set(_points "1 0 0|1.02 0.03 0|0 2.05 0.3")
set(_types "uchar|ushort|float|double|int|short|char")
set(_uchar "200 10 20|100 30 40|0 0 255")
set(_ushort "51400 2570 5140|25700 7710 10280|0 0 65535")
set(_float "0.78431374 0.039215688 0.078431375|0.39215687 0.11764706 0.15686275|0 0 1")
set(_double "${_float}")
set(_int "${_uchar}")
set(_short "${_uchar}")
set(_char "127 10 20|100 30 40|0 0 127")  # char holds 0..127: 127 is the brightest
string(REPLACE "|" ";" _points "${_points}")
string(REPLACE "|" ";" _types "${_types}")
foreach(_t IN LISTS _types)
  string(REPLACE "|" ";" _values "${_${_t}}")
  set(_ply "${_head}property ${_t} red\nproperty ${_t} green\nproperty ${_t} blue\nend_header\n")
  foreach(_i RANGE 2)
    list(GET _points ${_i} _p)
    list(GET _values ${_i} _v)
    string(APPEND _ply "${_p} ${_v}\n")
  endforeach()
  file(WRITE "${OUT}/${_t}.ply" "${_ply}")
  set(_expect "150 20 30;0 0 255")
  if(_t STREQUAL "char")
    set(_expect "114 20 30;0 0 127")
  endif()
  # map: the ColorOcTree .ot keeps the colours; the .bt cannot, and one note says so.
  run_tool(map -i "${OUT}/${_t}.ply" -r 0.1 -o "${OUT}/${_t}.ot" -o "${OUT}/${_t}.bt")
  expect_notes("${_stderr}" 1 "note: the map's colours are not kept by [^\n]*${_t}\\.bt"
               "map of ${_t} colours")
  expect_tree_id("${OUT}/${_t}.ot" ColorOcTree "map of ${_t} colours")
  expect_voxel_colours("${OUT}/${_t}.ot" "${_expect}" "map of ${_t} colours")
  # convert PLY to PLY keeps them, scaled to uchar.
  run_tool(convert "${OUT}/${_t}.ply" "${OUT}/${_t}_copy.ply" --encoding ascii)
  expect_notes("${_stderr}" 0 "" "convert ${_t}.ply")
  file(READ "${OUT}/${_t}_copy.ply" _copy)
  if(NOT _copy MATCHES "property uchar red\nproperty uchar green\nproperty uchar blue\n")
    message(FATAL_ERROR "convert ${_t}.ply wrote no colours:\n${_copy}")
  endif()
  if(_t STREQUAL "char")
    set(_want "1 0 0 127 10 20\n")
  else()
    set(_want "1 0 0 200 10 20\n1.02 0.03 0 100 30 40\n0 2.05 0.3 0 0 255\n")
  endif()
  if(NOT _copy MATCHES "${_want}")
    message(FATAL_ERROR "convert ${_t}.ply: colours not kept:\n${_copy}")
  endif()
endforeach()
message(STATUS "map and convert keep the colours of ${_types}")

# convert .ot -> .ot: a ColorOcTree stays one, byte for byte.
run_tool(convert "${OUT}/uchar.ot" "${OUT}/copy.ot")
expect_notes("${_stderr}" 0 "" "convert colour .ot to .ot")
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${OUT}/uchar.ot" "${OUT}/copy.ot"
                RESULT_VARIABLE _differ)
if(NOT _differ EQUAL 0)
  message(FATAL_ERROR "convert of a ColorOcTree .ot to .ot changed it")
endif()
# Formats without colour say so, once.
foreach(_ext bt voxels xyz pcd png)
  run_tool(convert "${OUT}/uchar.ot" "${OUT}/from_ot.${_ext}")
  expect_notes("${_stderr}" 1 "uchar\\.ot: note: the map's colours are not kept by [^\n]*from_ot\\.${_ext}"
               "convert colour .ot to .${_ext}")
endforeach()
foreach(_ext xyz pcd bin)
  run_tool(convert "${OUT}/uchar.ply" "${OUT}/from_ply.${_ext}")
  expect_notes("${_stderr}" 1 "uchar\\.ply: note: the cloud's colours are not kept by [^\n]*from_ply\\.${_ext}"
               "convert colour .ply to .${_ext}")
endforeach()
# A plain map converted: nothing to say.
run_tool(convert "${OUT}/uchar.bt" "${OUT}/plain.ot")
expect_notes("${_stderr}" 0 "" "convert plain .bt")
expect_tree_id("${OUT}/plain.ot" OcTree "convert plain .bt")

# --init-map of a ColorOcTree with clouds that have no colour: the colours stay (the rays of
# these points miss the coloured voxels).
file(WRITE "${OUT}/plain.ply" "${_head}end_header\n-1 0 0\n0 -1 0.5\n0 -1 -0.5\n")
run_tool(map -i "${OUT}/plain.ply" --init-map "${OUT}/uchar.ot" -o "${OUT}/init.ot")
expect_notes("${_stderr}" 0 "" "--init-map of a colour map")
expect_tree_id("${OUT}/init.ot" ColorOcTree "--init-map of a colour map")
expect_voxel_colours("${OUT}/init.ot" "150 20 30;0 0 255" "--init-map of a colour map")
# With coloured clouds: a voxel's colour from the map counts as one point of that colour.
string(REPLACE "vertex 3" "vertex 1" _head1 "${_head}")
file(WRITE "${OUT}/more.ply"
     "${_head1}property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n0 2.05 0.3 0 0 55\n")
run_tool(map -i "${OUT}/more.ply" --init-map "${OUT}/uchar.ot" -o "${OUT}/more.ot" -o "${OUT}/more.bt")
expect_notes("${_stderr}" 1 "note: the map's colours are not kept by [^\n]*more\\.bt"
             "--init-map of a colour map with coloured clouds")
expect_voxel_colours("${OUT}/more.ot" "150 20 30;0 0 155" "--init-map with coloured clouds")
# --no-color: a plain OcTree, no note.
run_tool(map -i "${OUT}/plain.ply" --init-map "${OUT}/uchar.ot" -o "${OUT}/nocolor.ot" -o
         "${OUT}/nocolor.bt" --no-color)
expect_notes("${_stderr}" 0 "" "--init-map --no-color")
expect_tree_id("${OUT}/nocolor.ot" OcTree "--init-map --no-color")
# Several files without colour: still one note, naming them all.
run_tool(map -i "${OUT}/uchar.ply" -r 0.1 -o "${OUT}/a.bt" -o "${OUT}/a.voxels" -o "${OUT}/a.ot")
expect_notes("${_stderr}" 1 "not kept by [^\n]*a\\.bt, [^\n]*a\\.voxels \\(formats without colour"
             "map with two files without colour")
message(STATUS "convert and --init-map keep ColorOcTree colours; formats without colour say so once")
file(REMOVE_RECURSE "${OUT}")
