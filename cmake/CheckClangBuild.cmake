# Builds the test suite and the tool with clang++ and -Werror in a nested build tree, so CI
# proves the code warning-clean on both compilers (the main build uses the default compiler).
#   -DCLANGXX=<clang++> -DROOT=<project root> -DWORK_DIR=<build dir>
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${ROOT}" -B "${WORK_DIR}"
    -DCMAKE_CXX_COMPILER=${CLANGXX} -DCMAKE_BUILD_TYPE=Debug -DKNNOCC_WERROR=ON
    -DKNNOCC_BUILD_BENCH=OFF
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "configuring with ${CLANGXX} failed")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${WORK_DIR}" -j2
    --target knnocc_tests knnocc_tool example_insert_point_cloud example_custom_point_type
            example_knn_mapping knnocc_noexcept_smoke
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "building with ${CLANGXX} -Werror failed")
endif()
