// io::Error (io/error.hpp): the file and the problem.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <knnocc/io/sequence.hpp>

#include "test_support.hpp"

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::Point3f;

TEST_CASE("io.error carries file and problem") {
  const io::Error e("a/b.ply", "something broke");
  CHECK(std::string(e.what()) == "a/b.ply: something broke");
  CHECK(e.file() == "a/b.ply");
  CHECK(e.problem() == "something broke");
  const std::runtime_error& base = e;
  CHECK(std::string(base.what()) == "a/b.ply: something broke");
}
