# Decompress a .bz2 file for the test data fixture (run with cmake -P).
#   -DBZIP2=<bzip2 executable> -DINPUT=<file.bz2> -DOUTPUT=<file>
# Writes to a temporary name and renames, so an interrupted run never leaves a
# truncated OUTPUT behind; does nothing if OUTPUT already exists and is newer.
foreach(_var BZIP2 INPUT OUTPUT)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "DecompressBz2.cmake: -D${_var}=... is required")
  endif()
endforeach()
if(NOT EXISTS "${INPUT}")
  message(FATAL_ERROR "DecompressBz2.cmake: input ${INPUT} does not exist")
endif()

# IS_NEWER_THAN is also true for equal timestamps, hence the NOT on the reverse.
if(EXISTS "${OUTPUT}" AND NOT "${INPUT}" IS_NEWER_THAN "${OUTPUT}")
  message(STATUS "Up to date: ${OUTPUT}")
  return()
endif()

get_filename_component(_dir "${OUTPUT}" DIRECTORY)
file(MAKE_DIRECTORY "${_dir}")
string(RANDOM LENGTH 8 _suffix)
set(_tmp "${OUTPUT}.tmp-${_suffix}")
execute_process(
  COMMAND "${BZIP2}" -dc "${INPUT}"
  OUTPUT_FILE "${_tmp}"
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  file(REMOVE "${_tmp}")
  message(FATAL_ERROR "DecompressBz2.cmake: '${BZIP2} -dc ${INPUT}' failed: ${_rc}")
endif()
file(RENAME "${_tmp}" "${OUTPUT}")
message(STATUS "Decompressed ${INPUT} -> ${OUTPUT}")
