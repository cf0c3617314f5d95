# The ORB-SLAM exporter (examples/orbslam) end to end: a simulated ORB-SLAM run through the
# stand-in headers writes a sequence folder, and the knnocc tool maps it.
#   -DSIMULATE=<exe>   tests/orbslam_standins/simulate_run built for one API
#   -DTOOL=<exe>       the knnocc tool
#   -DDIR=<path>       scratch folder (emptied first)
# Checks: the run's keyframes and correction snapshots; the clouds carry ids and the per-point
# evidence (found, visible, observations); for the OctoMap and k-NN models the map built with
# --corrections equals, voxel for voxel, the map of the final trajectory built from scratch; the
# robust model reads the clouds (their ids) too.
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
