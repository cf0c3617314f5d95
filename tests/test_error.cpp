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

TEST_CASE("io.error shows control bytes escaped and keeps what follows a NUL") {
  CHECK(io::printable("plain text / path_1.ply") == "plain text / path_1.ply");
  CHECK(io::printable("a\x1b[31mred") == "a\\x1b[31mred");
  CHECK(io::printable(std::string("id\0tail", 7)) == "id\\x00tail");
  CHECK(io::printable("tab\there\nnew\x7f") == "tab\\x09here\\x0anew\\x7f");
  CHECK(io::printable("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82") ==
        "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82");  // UTF-8 characters stay
  CHECK(io::printable("\xc2\x9b"
                      "2J") == "\\xc2\\x9b2J");  // a C1 control (CSI) in UTF-8
  CHECK(io::printable("\xff\xc3(\xe2\x82") == "\\xff\\xc3(\\xe2\\x82");  // not UTF-8
  CHECK(io::printable("\xed\xa0\x80") == "\\xed\\xa0\\x80");             // an encoded surrogate
  CHECK(io::printable(io::printable("a\x1b\\x1b")) == io::printable("a\x1b\\x1b"));  // idempotent
  const io::Error e(std::string("dir/\x1b[2Jname.ply", 16), std::string("bad 'x\0y'", 9));
  CHECK(std::string(e.what()) == "dir/\\x1b[2Jname.ply: bad 'x\\x00y'");
  CHECK(e.file() == "dir/\\x1b[2Jname.ply");
  CHECK(e.problem() == "bad 'x\\x00y'");
}
