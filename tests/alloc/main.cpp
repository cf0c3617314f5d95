// doctest entry point for knnocc_alloc_tests: the tests that count allocations
// (counting_new.hpp). tests/alloc/CMakeLists.txt picks up tests/alloc/test_*.cpp.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
