// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The plain-text indexes of tile sets and rated-keyframe folders (tile_set.hpp, rated_store.hpp):
// one record per line, words separated by spaces, read with one clear error naming the file and
// the line for anything that is not exactly what the writer writes. Numbers are written so that
// they read back bit for bit (floats and doubles in their shortest round-trip form).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "../../io/detail/file_text.hpp"
#include "../../io/error.hpp"
#include "../../sensor/rated_keyframe.hpp"

namespace knnocc::tiles::detail {

/// A number as text that reads back to the same value.
inline std::string number_text(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}
inline std::string number_text(float v) {
  char text[40];
  char* end = io::detail::format_float_roundtrip(text, text + sizeof text - 1, v);
  *end = '\0';
  return text;
}
inline std::string number_text(std::int64_t v) { return std::to_string(v); }
inline std::string number_text(std::uint64_t v) { return std::to_string(v); }

/// A free text (a path, a model's options) as one word: '%', bytes below '!' and DEL as %XX.
inline std::string escape_word(const std::string& s) {
  std::string out;
  char hex[4];
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u == 0x7f || c == '%') {
      std::snprintf(hex, sizeof hex, "%%%02X", u);
      out += hex;
    } else {
      out += c;
    }
  }
  return out.empty() ? "%00" : out;  // an empty text stays one word
}
inline std::string unescape_word(const std::string& s) {
  if (s == "%00") return {};
  auto hex = [](char c) {
    return c >= '0' && c <= '9' ? c - '0' : c >= 'A' && c <= 'F' ? c - 'A' + 10 : -1;
  };
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() + 1 && hex(s[i + 1]) >= 0 && hex(s[i + 2]) >= 0) {
      out += static_cast<char>(hex(s[i + 1]) * 16 + hex(s[i + 2]));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

/// The lines of an index file, split into words, with typed reads that fail as
/// "FILE: line N: ...".
class IndexLines {
 public:
  /// Reads `path` (io::Error when it cannot be read); blank lines are skipped.
  explicit IndexLines(const std::string& path) : path_(path) {
    io::detail::for_each_file_line(path, [&](std::size_t line, const char* b, const char* e) {
      std::vector<std::string> words = io::detail::split_words(b, e);
      if (!words.empty()) lines_.push_back({line, std::move(words)});
    });
  }

  const std::string& path() const { return path_; }
  bool done() const { return next_ >= lines_.size(); }

  /// The next line, which must start with `keyword` and have `words` words after it (-1: any
  /// number, at least one).
  const std::vector<std::string>& take(const std::string& keyword, int words) {
    if (done())
      throw io::Error(path_, "the index ends before its '" + keyword + "' line (truncated?)");
    const Line& l = lines_[next_++];
    line_ = l.number;
    if (l.words[0] != keyword) fail("expected '" + keyword + "', found '" + l.words[0] + "'");
    if (words >= 0 ? l.words.size() != static_cast<std::size_t>(words) + 1 : l.words.size() < 2)
      fail("'" + keyword + "' needs " + (words >= 0 ? std::to_string(words) : "some") +
           " value(s), found " + std::to_string(l.words.size() - 1));
    return l.words;
  }
  /// The keyword of the next line ("" at the end).
  std::string peek() const { return done() ? std::string() : lines_[next_].words[0]; }

  [[noreturn]] void fail(const std::string& what) const {
    throw io::Error(path_, "line " + std::to_string(line_) + ": " + what);
  }

  template <class T>
  T integer(const std::string& word, const char* what) const {
    T v{};
    if (!io::detail::parse_int_token(word.data(), word.data() + word.size(), v))
      fail(std::string(what) + " '" + word + "' is not an integer in range");
    return v;
  }
  double real(const std::string& word, const char* what) const {
    double v = 0;
    if (!io::detail::parse_real_token(word.data(), word.data() + word.size(), v))
      fail(std::string(what) + " '" + word + "' is not a number");
    return v;
  }
  float real_float(const std::string& word, const char* what) const {
    float v = 0;
    if (!io::detail::parse_real_token(word.data(), word.data() + word.size(), v))
      fail(std::string(what) + " '" + word + "' is not a number");
    return v;
  }
  /// `word` must be `expect` (the name of the value that follows).
  void expect_word(const std::string& word, const char* expect) const {
    if (word != expect) fail("expected '" + std::string(expect) + "', found '" + word + "'");
  }

 private:
  struct Line {
    std::size_t number;
    std::vector<std::string> words;
  };
  std::string path_;
  std::vector<Line> lines_;
  std::size_t next_ = 0;
  std::size_t line_ = 0;
};

inline const char* kind_name(RatingKind k) {
  return k == RatingKind::fixed ? "fixed" : k == RatingKind::rated ? "rated" : "layered";
}

/// The `integration` and `occupancy` lines of an index.
inline std::string integration_lines(const IntegrationParams& p) {
  return std::string("integration ") + kind_name(p.kind) + " hit " + number_text(p.hit) + " miss " +
         number_text(p.miss) + " strong_miss " + number_text(p.layers.strong_miss) + " weak_miss " +
         number_text(p.layers.weak_miss) + " weak_range " + number_text(p.layers.weak_range) +
         " max_range " + number_text(p.max_range) + " discretize " + (p.discretize ? "1" : "0") +
         "\noccupancy clamp_min " + number_text(p.occupancy.clamp_min) + " clamp_max " +
         number_text(p.occupancy.clamp_max) + " threshold " +
         number_text(p.occupancy.occupancy_threshold) + "\n";
}

inline IntegrationParams read_integration(IndexLines& in) {
  IntegrationParams p;
  const std::vector<std::string>& w = in.take("integration", 15);
  if (w[1] == "fixed")
    p.kind = RatingKind::fixed;
  else if (w[1] == "rated")
    p.kind = RatingKind::rated;
  else if (w[1] == "layered")
    p.kind = RatingKind::layered;
  else
    in.fail("unknown integration kind '" + w[1] + "'");
  const char* names[] = {"hit",        "miss",      "strong_miss", "weak_miss",
                         "weak_range", "max_range", "discretize"};
  for (int i = 0; i < 7; ++i) in.expect_word(w[static_cast<std::size_t>(2 + 2 * i)], names[i]);
  p.hit = in.real_float(w[3], "hit");
  p.miss = in.real_float(w[5], "miss");
  p.layers.strong_miss = in.real_float(w[7], "strong_miss");
  p.layers.weak_miss = in.real_float(w[9], "weak_miss");
  p.layers.weak_range = in.real(w[11], "weak_range");
  p.max_range = in.real(w[13], "max_range");
  if (w[15] != "0" && w[15] != "1") in.fail("discretize must be 0 or 1");
  p.discretize = w[15] == "1";
  const std::vector<std::string>& o = in.take("occupancy", 6);
  in.expect_word(o[1], "clamp_min");
  in.expect_word(o[3], "clamp_max");
  in.expect_word(o[5], "threshold");
  p.occupancy.clamp_min = in.real_float(o[2], "clamp_min");
  p.occupancy.clamp_max = in.real_float(o[4], "clamp_max");
  p.occupancy.occupancy_threshold = in.real_float(o[6], "threshold");
  const OccupancyParams& c = p.occupancy;
  if (!(c.clamp_min < c.clamp_max && c.occupancy_threshold >= c.clamp_min &&
        c.occupancy_threshold <= c.clamp_max))
    in.fail("clamping must satisfy clamp_min < clamp_max and clamp_min <= threshold <= clamp_max");
  if (p.max_range == 0.0 || p.max_range != p.max_range) in.fail("max_range must not be 0 or NaN");
  return p;
}

}  // namespace knnocc::tiles::detail
