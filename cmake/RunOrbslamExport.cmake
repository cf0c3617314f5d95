# The ORB-SLAM exporter (examples/orbslam) end to end: a simulated ORB-SLAM run through the
# stand-in headers writes a sequence folder, and the knnocc tool maps it.
#   -DSIMULATE=<exe>   tests/orbslam_standins/simulate_run built for one API
#   -DTOOL=<exe>       the knnocc tool
#   -DDIR=<path>       scratch folder (emptied first)
# Checks: the run's keyframes and correction snapshots; the clouds carry ids and the per-point
# evidence (found, visible, observations); for the OctoMap and k-NN models the map built with
# --corrections equals, voxel for voxel, the map of the final trajectory built from scratch; the
# robust model reads the clouds (their ids) too; and README's "From ORB-SLAM to Nav2" commands,
# word for word but for the folder, give the .bt, the picture, the page and the Nav2 map.
function(run_checked)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
  message(STATUS "${ARGN}\nexit ${_rc}\n${_out}${_err}")
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "failed: ${ARGN}")
  endif()
  set(_out "${_out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${DIR}")
file(MAKE_DIRECTORY "${DIR}")
set(_run "${DIR}/run")
run_checked("${SIMULATE}" "${_run}")
if(NOT _out MATCHES "^keyframes 40 snapshots 3\n")
  message(FATAL_ERROR "expected 40 keyframes and 3 snapshots")
endif()
file(READ "${_run}/clouds/000000.ply" _head LIMIT 400)
if(NOT _head MATCHES "property uint id\nproperty uint found\nproperty uint visible\nproperty uint observations\nend_header")
  message(FATAL_ERROR "clouds/000000.ply lacks the id and evidence properties")
endif()

# The final trajectory: the last snapshot (the exporter writes one at finish()).
file(GLOB _snapshots "${_run}/corrections/after_*.txt")
list(SORT _snapshots)
list(GET _snapshots -1 _last)
set(_final "${DIR}/final")
file(COPY "${_run}/clouds" DESTINATION "${_final}")
configure_file("${_last}" "${_final}/poses.txt" COPYONLY)

foreach(_model octomap knn)
  run_checked("${TOOL}" map --input "${_run}" --corrections "${_run}/corrections" --res 0.1
              --model ${_model} --out-voxels "${DIR}/live_${_model}.txt")
  if(NOT _out MATCHES "corrections 3 reposed_keyframes [1-9]")
    message(FATAL_ERROR "the three snapshots were not applied")
  endif()
  run_checked("${TOOL}" map --input "${_final}" --res 0.1 --model ${_model}
              --out-voxels "${DIR}/final_${_model}.txt")
  if(NOT _out MATCHES "clouds 40 points [0-9]+ occupied [1-9][0-9]+ free [1-9]")
    message(FATAL_ERROR "the final map is empty")
  endif()
  execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${DIR}/live_${_model}.txt"
                          "${DIR}/final_${_model}.txt" RESULT_VARIABLE _differ)
  if(_differ)
    message(FATAL_ERROR "${_model}: the map with --corrections differs from the final trajectory's")
  endif()
endforeach()
run_checked("${TOOL}" map --input "${_run}" --res 0.1 --model robust)
if(NOT _out MATCHES "knn k [0-9]+ map_points [1-9][0-9]+ ")
  message(FATAL_ERROR "the robust model did not read the map-point ids")
endif()

# README, "From ORB-SLAM to Nav2" (run1 is the simulated run's folder).
set(_readme "${DIR}/readme")
file(MAKE_DIRECTORY "${_readme}")
file(COPY "${_run}/" DESTINATION "${_readme}/run1")
execute_process(COMMAND "${CMAKE_COMMAND}" -E chdir "${_readme}" "${TOOL}" map -i run1
                        --corrections run1/corrections --model knn --res 0.05 -o run1.bt -o run1.png
                RESULT_VARIABLE _rc)
execute_process(COMMAND "${CMAKE_COMMAND}" -E chdir "${_readme}" "${TOOL}" view run1.bt --path run1
                RESULT_VARIABLE _rc2)
execute_process(COMMAND "${CMAKE_COMMAND}" -E chdir "${_readme}" "${TOOL}" convert run1.bt run1.yaml
                        --grid-z -1.0:1.0 --up -y
                RESULT_VARIABLE _rc3 OUTPUT_VARIABLE _grid)
message(STATUS "README commands: exit ${_rc} ${_rc2} ${_rc3}\n${_grid}")
if(NOT (_rc EQUAL 0 AND _rc2 EQUAL 0 AND _rc3 EQUAL 0))
  message(FATAL_ERROR "a README command failed")
endif()
foreach(_f run1.bt run1.png run1.html run1.yaml run1.pgm)
  if(NOT EXISTS "${_readme}/${_f}")
    message(FATAL_ERROR "README's commands did not write ${_f}")
  endif()
endforeach()
# The room's walls in the grid: occupied and free cells, the unknown ones only outside.
if(NOT _grid MATCHES "grid run1.yaml: [0-9]+ x [0-9]+ cells of 0.05 m, up -y, heights -1:1 m: occupied [1-9][0-9][0-9]+ free [1-9][0-9][0-9][0-9]+ unknown")
  message(FATAL_ERROR "the Nav2 map does not show the room")
endif()
