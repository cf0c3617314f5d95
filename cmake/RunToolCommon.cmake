# What the cmake -P check scripts that drive the knnocc tool share (include() it; TOOL is the
# executable).

# Runs the tool; fails unless it exits 0. Leaves stdout and stderr in _stdout and _stderr.
function(run_tool)
  execute_process(COMMAND "${TOOL}" ${ARGN} RESULT_VARIABLE _rc OUTPUT_VARIABLE _o
                  ERROR_VARIABLE _e)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "knnocc ${ARGN}: exit ${_rc}\n${_o}\n${_e}")
  endif()
  set(_stdout "${_o}" PARENT_SCOPE)
  set(_stderr "${_e}" PARENT_SCOPE)
endfunction()
