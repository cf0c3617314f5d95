# ctest python.install: `cmake --install --component python` into a fresh prefix, then the module
# imported from there by its interpreter; and the prefix configured for real installs
# (CMAKE_INSTALL_PREFIX, /usr/local by default) puts it on that interpreter's own sys.path.
#   -DBUILD_DIR=<build> -DPREFIX=<scratch prefix> -DPYTHON=<interpreter>
#   -DINSTALL_DIR=<KNNOCC_PYTHON_INSTALL_DIR> -DDEFAULT_PREFIX=<CMAKE_INSTALL_PREFIX>
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}"
                        --component python
  RESULT_VARIABLE _rc OUTPUT_QUIET)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed")
endif()
set(_dir "${PREFIX}/${INSTALL_DIR}")
file(GLOB _module "${_dir}/knnocc/_knnocc.*.so" "${_dir}/knnocc/_knnocc*.pyd")
if(NOT _module OR NOT EXISTS "${_dir}/knnocc/__init__.pyi" OR NOT EXISTS "${_dir}/knnocc/dask/__main__.py")
  message(FATAL_ERROR "no package (module, stub, knnocc.dask) in ${_dir}")
endif()
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env --unset=PYTHONPATH "${PYTHON}" -c "
import sys
sys.path.insert(0, '${_dir}')
import knnocc, knnocc.dask, numpy as np
assert knnocc.__file__.startswith('${_dir}'), knnocc.__file__
assert knnocc.OccupancyMap.__module__ == 'knnocc', knnocc.OccupancyMap.__module__
m = knnocc.OccupancyMap(0.1)
m.insert_point_cloud(np.array([[1.0, 0.0, 0.0]]), (0, 0, 0))
assert m.count_voxels() == (1, 9), m.count_voxels()
print('imported', knnocc.__file__)"
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "the installed module does not import")
endif()

execute_process(
  COMMAND "${PYTHON}" -I -c "import sys; print('\\n'.join(sys.path))"
  OUTPUT_VARIABLE _path)
string(REPLACE "\n" ";" _path "${_path}")
list(FIND _path "${DEFAULT_PREFIX}/${INSTALL_DIR}" _at)
if(_at GREATER -1)
  message(STATUS "${DEFAULT_PREFIX}/${INSTALL_DIR} is on ${PYTHON}'s sys.path")
elseif(DEFAULT_PREFIX STREQUAL "/usr/local" OR DEFAULT_PREFIX STREQUAL "/usr")
  message(FATAL_ERROR "cmake --install would put the module in ${DEFAULT_PREFIX}/${INSTALL_DIR}, "
                      "which is not on ${PYTHON}'s sys.path: ${_path}")
else()
  message(STATUS "CMAKE_INSTALL_PREFIX ${DEFAULT_PREFIX}: add ${DEFAULT_PREFIX}/${INSTALL_DIR} "
                 "to PYTHONPATH")
endif()
