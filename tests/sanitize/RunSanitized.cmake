# AddressSanitizer + UndefinedBehaviorSanitizer run of the test suite (ctest test
# sanitizer.asan_ubsan): the whole project configured in a nested tree with clang++,
# KNNOCC_SANITIZE=address,undefined and -Werror (so this build also proves every target
# warning-free on clang), then the doctest suite, the tool's CLI checks, the examples, the
# no-exceptions smoke test and the libFuzzer harnesses (tests/fuzz, FUZZ_SECONDS each) run there.
# Any report is fatal (-fno-sanitize-recover=all). The Python module is left out: an instrumented
# module cannot be loaded into the uninstrumented interpreter.
# Kept within CI's budget: line tables only (file:line in reports, no variable info) and a unity
# build (the test sources compiled in batches of 13, so the headers' templates are instrumented
# once per batch instead of once per test file): a third less building. Fuzzing 8 s per
# harness is a smoke run; fuzz longer by hand (tests/fuzz/CMakeLists.txt, KNNOCC_FUZZ_SECONDS).
#   -DCXX=<clang++> -DROOT=<project root> -DWORK_DIR=<build dir> [-DFUZZ_SECONDS=<s>]
if(NOT FUZZ_SECONDS)
  set(FUZZ_SECONDS 8)
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${ROOT}" -B "${WORK_DIR}"
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=RelWithDebInfo
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only" -DCMAKE_UNITY_BUILD=ON
    -DCMAKE_UNITY_BUILD_BATCH_SIZE=13 -DKNNOCC_SANITIZE=address,undefined -DKNNOCC_WERROR=ON
    -DKNNOCC_BUILD_BENCH=OFF -DKNNOCC_INSTALL=OFF -DKNNOCC_BUILD_FUZZERS=ON
    -DKNNOCC_BUILD_PYTHON=OFF
    -DKNNOCC_FUZZ_SECONDS=${FUZZ_SECONDS}
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "configuring the sanitizer build failed")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" --build "${WORK_DIR}" -j2
    --target all
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "building with clang -Werror -fsanitize=address,undefined failed")
endif()
set(ENV{ASAN_OPTIONS} "detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1")
set(ENV{UBSAN_OPTIONS} "print_stacktrace=1:halt_on_error=1")
# The tool's byte-for-byte tile checks on real data (cli.tiles_<data>: every model mapped four
# times per input) run in the main build only; here the library's tile tests and the tool's small
# tile checks walk the same code.
execute_process(COMMAND "${CMAKE_CTEST_COMMAND}" --test-dir "${WORK_DIR}" --output-on-failure -j2
    -R "^(fixture|doctest|cli|example|noexcept|fuzz)\\."
    -E "^cli\\.tiles_(tum|stereo|scan_dat|drive)$"
  RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "tests under AddressSanitizer + UndefinedBehaviorSanitizer failed")
endif()
