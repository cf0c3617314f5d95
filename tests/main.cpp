// doctest entry point for knnocc_tests. Test cases live in tests/test_*.cpp,
// which tests/CMakeLists.txt picks up automatically.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
