#include <knnocc/version.hpp>

#include <doctest/doctest.h>

#include <string>

TEST_SUITE("version") {
  TEST_CASE("version string matches the numeric components") {
    const std::string expected = std::to_string(KNNOCC_VERSION_MAJOR) + "." +
                                 std::to_string(KNNOCC_VERSION_MINOR) + "." +
                                 std::to_string(KNNOCC_VERSION_PATCH);
    CHECK(std::string(KNNOCC_VERSION_STRING) == expected);
    CHECK(std::string(knnocc::version_string) == expected);
  }
}
