# .ci/run runs README's second set-up command (the whole test suite), word for word.
#   -DROOT=<repository root>
file(STRINGS "${ROOT}/README.md" _readme REGEX "^apt-get ")
file(STRINGS "${ROOT}/.ci/run" _ci REGEX "^apt-get ")
list(LENGTH _readme _n)
if(NOT _n EQUAL 2)
  message(FATAL_ERROR "README.md should start with two set-up commands, found ${_n}")
endif()
list(GET _readme 1 _test_command)
if(NOT _ci STREQUAL _test_command)
  message(FATAL_ERROR ".ci/run differs from README's test command:\n  .ci/run: ${_ci}\n  README: ${_test_command}")
endif()
