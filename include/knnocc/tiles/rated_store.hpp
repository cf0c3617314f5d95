// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A folder of rated keyframes (sensor/rated_keyframe.hpp): what the rating pass of a run writes
// once (tiles/rating_pass.hpp) and every tile reads (tiles/tile_mapping.hpp), in this process or
// on other machines sharing the folder.
//
//   rated.txt        the index: the map's resolution and key width, the run's integration
//                    constants, then one line per keyframe: its file, point and edit counts, and
//                    the box of keys it can update (keyframe_reach), or "none"
//   NNNNNN.rkf       one keyframe, binary little-endian:
//                      "KNNOCCRK", u32 version (1), u8 kind (0 fixed, 1 rated, 2 layered), 3 zero
//                      bytes, u64 points, u64 edits, f32 origin x y z,
//                      points x f32 x y z,
//                      rated:   points x f32 log-odds, points x u8 casts a ray (0/1)
//                      layered: points x f32 log-odds, points x u8 hit (0/1), points x u8 layer
//                               (0 none, 1 strong, 2 weak)
//                      edits x (u64 key, f32 delta, u8 lower-if-occupied (0/1)),
//                      u64 FNV-1a of all the bytes before it.
// A file that does not decode exactly so (length, values, checksum) is an io::Error naming it.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "../core/grid.hpp"
#include "../core/key.hpp"
#include "../io/atomic_file.hpp"
#include "../io/detail/bytes.hpp"
#include "../io/detail/file_text.hpp"
#include "../io/error.hpp"
#include "../sensor/rated_keyframe.hpp"
#include "detail/index_text.hpp"
#include "tile_integrator.hpp"

namespace knnocc::tiles {

namespace detail {

inline constexpr char kRatedMagic[8] = {'K', 'N', 'N', 'O', 'C', 'C', 'R', 'K'};
inline constexpr std::uint32_t kRatedVersion = 1;

/// 64-bit FNV-1a.
inline std::uint64_t fnv1a(const char* p, std::size_t n, std::uint64_t h = 0xcbf29ce484222325ULL) {
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 0x100000001b3ULL;
  }
  return h;
}

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  io::detail::store_le(b, v);
  out.append(b, sizeof(T));
}

}  // namespace detail

/// The bytes of one rated keyframe file.
inline std::string encode_rated_keyframe(const RatedKeyframe& rk) {
  using detail::put;
  const std::size_t n = rk.points.size();
  std::string out(detail::kRatedMagic, 8);
  put<std::uint32_t>(out, detail::kRatedVersion);
  put<std::uint8_t>(out, static_cast<std::uint8_t>(rk.kind));
  out.append(3, '\0');
  put<std::uint64_t>(out, n);
  put<std::uint64_t>(out, rk.edits.size());
  put(out, rk.origin.x);
  put(out, rk.origin.y);
  put(out, rk.origin.z);
  for (const Point3f& p : rk.points) {
    put(out, p.x);
    put(out, p.y);
    put(out, p.z);
  }
  if (rk.kind == RatingKind::rated) {
    for (const EndpointRating& r : rk.ratings) put(out, r.logodds);
    for (const EndpointRating& r : rk.ratings) put<std::uint8_t>(out, r.casts_ray ? 1 : 0);
  } else if (rk.kind == RatingKind::layered) {
    for (const LayeredRating& r : rk.layered) put(out, r.logodds);
    for (const LayeredRating& r : rk.layered) put<std::uint8_t>(out, r.hit ? 1 : 0);
    for (const LayeredRating& r : rk.layered)
      put<std::uint8_t>(out, static_cast<std::uint8_t>(r.ray));
  }
  for (const MapEdit& e : rk.edits) {
    put(out, e.key);
    put(out, e.delta);
    put<std::uint8_t>(out, e.lower_if_occupied ? 1 : 0);
  }
  put(out, detail::fnv1a(out.data(), out.size()));
  return out;
}

/// Decodes one rated keyframe file's bytes into `rk` (io::Error naming `path` when they are not
/// exactly a rated keyframe: length, kind, flags, non-finite ratings, the checksum).
inline void decode_rated_keyframe(const std::string& path, const char* data, std::size_t size,
                                  RatedKeyframe& rk) {
  const auto* p = reinterpret_cast<const unsigned char*>(data);
  constexpr std::size_t head = 8 + 4 + 4 + 8 + 8 + 12;
  if (size < head + 8 || std::memcmp(data, detail::kRatedMagic, 8) != 0)
    throw io::Error(path, "not a knnocc rated keyframe file");
  if (io::detail::load_le<std::uint64_t>(p + size - 8) != detail::fnv1a(data, size - 8))
    throw io::Error(path, "checksum does not match: the file is damaged");
  if (io::detail::load_le<std::uint32_t>(p + 8) != detail::kRatedVersion)
    throw io::Error(path, "rated keyframe file of an unknown version");
  const unsigned kind = p[12];
  if (kind > 2) throw io::Error(path, "unknown rating kind " + std::to_string(kind));
  rk.clear();
  rk.kind = static_cast<RatingKind>(kind);
  const auto n = io::detail::load_le<std::uint64_t>(p + 16);
  const auto m = io::detail::load_le<std::uint64_t>(p + 24);
  const std::uint64_t per_point = 12 + (rk.kind == RatingKind::rated     ? 5
                                        : rk.kind == RatingKind::layered ? 6
                                                                         : 0);
  if (n > (size - head - 8) / per_point || m > (size - head - 8) / 13 ||
      head + n * per_point + m * 13 + 8 != size)
    throw io::Error(path, "file length does not match its point and edit counts");
  rk.origin = {io::detail::load_le<float>(p + 32), io::detail::load_le<float>(p + 36),
               io::detail::load_le<float>(p + 40)};
  const unsigned char* q = p + head;
  rk.points.resize(n);
  for (Point3f& pt : rk.points) {
    pt = {io::detail::load_le<float>(q), io::detail::load_le<float>(q + 4),
          io::detail::load_le<float>(q + 8)};
    q += 12;
  }
  auto flag = [&](unsigned char b, unsigned max) {
    if (b > max) throw io::Error(path, "a point's flag is " + std::to_string(b));
    return b;
  };
  auto logodds = [&](const unsigned char* at) {
    const float v = io::detail::load_le<float>(at);
    if (!std::isfinite(v)) throw io::Error(path, "a point's log-odds is not finite");
    return v;
  };
  if (rk.kind == RatingKind::rated) {
    rk.ratings.resize(n);
    for (std::size_t i = 0; i < n; ++i) rk.ratings[i].logodds = logodds(q + 4 * i);
    q += 4 * n;
    for (std::size_t i = 0; i < n; ++i) rk.ratings[i].casts_ray = flag(q[i], 1) != 0;
    q += n;
  } else if (rk.kind == RatingKind::layered) {
    rk.layered.resize(n);
    for (std::size_t i = 0; i < n; ++i) rk.layered[i].logodds = logodds(q + 4 * i);
    q += 4 * n;
    for (std::size_t i = 0; i < n; ++i) rk.layered[i].hit = flag(q[i], 1) != 0;
    q += n;
    for (std::size_t i = 0; i < n; ++i) rk.layered[i].ray = static_cast<RayLayer>(flag(q[i], 2));
    q += n;
  }
  rk.edits.resize(m);
  for (MapEdit& e : rk.edits) {
    e.key = io::detail::load_le<std::uint64_t>(q);
    e.delta = io::detail::load_le<float>(q + 8);
    if (!std::isfinite(e.delta)) throw io::Error(path, "an edit's log-odds is not finite");
    e.lower_if_occupied = flag(q[12], 1) != 0;
    q += 13;
  }
}

/// What rated.txt says of one keyframe.
struct RatedKeyframeEntry {
  std::string file;  ///< NNNNNN.rkf, in the folder
  std::uint64_t points = 0, edits = 0;
  /// The keys it can update (keyframe_reach; as per-axis indices of the run's keys), or none.
  std::optional<std::array<std::int64_t, 6>> reach;
};

/// What a rating pass counted over a run (for the summary line of `knnocc map`).
struct RatingTotals {
  std::uint64_t clouds = 0, points = 0, nonfinite = 0, out_of_range = 0, rated = 0, rays = 0;
};

/// A folder of rated keyframes, read.
class RatedStore {
 public:
  /// Reads `dir`/rated.txt (io::Error naming it and the line for anything wrong).
  static RatedStore open(const std::string& dir) {
    RatedStore s;
    s.dir_ = dir;
    detail::IndexLines in((std::filesystem::path(dir) / "rated.txt").string());
    const auto& head = in.take("knnocc", 3);
    if (head[1] != "rated" || head[2] != "keyframes" || head[3] != "1")
      in.fail("not a knnocc rated keyframes index (version 1)");
    s.resolution_ = in.real(in.take("resolution", 1)[1], "resolution");
    if (!(s.resolution_ >= Grid<OcKey>::min_resolution && s.resolution_ < 1e6))
      in.fail("resolution out of range");
    s.key_bits_ = in.integer<int>(in.take("key_bits", 1)[1], "key_bits");
    if (s.key_bits_ != 16 && s.key_bits_ != 21) in.fail("key_bits must be 16 or 21");
    s.params_ = detail::read_integration(in);
    const auto& t = in.take("totals", 12);
    const char* names[] = {"clouds", "points", "nonfinite", "out_of_range", "rated", "rays"};
    std::uint64_t* fields[] = {&s.totals_.clouds,       &s.totals_.points, &s.totals_.nonfinite,
                               &s.totals_.out_of_range, &s.totals_.rated,  &s.totals_.rays};
    for (int i = 0; i < 6; ++i) {
      in.expect_word(t[static_cast<std::size_t>(1 + 2 * i)], names[i]);
      *fields[i] = in.integer<std::uint64_t>(t[static_cast<std::size_t>(2 + 2 * i)], names[i]);
    }
    const auto count = in.integer<std::uint64_t>(in.take("keyframes", 1)[1], "keyframes");
    if (count > (std::uint64_t{1} << 32)) in.fail("too many keyframes");
    const std::int64_t extent = std::int64_t{1} << s.key_bits_;
    for (std::uint64_t i = 0; i < count; ++i) {
      if (in.peek() != "k") in.fail("expected " + std::to_string(count) + " keyframe lines");
      const auto& w = in.take("k", -1);
      if (w.size() != 6 && w.size() != 12) in.fail("a keyframe line has 5 or 11 values");
      RatedKeyframeEntry e;
      if (in.integer<std::uint64_t>(w[1], "keyframe") != i) in.fail("keyframes out of order");
      e.file = w[2];
      if (e.file.find('/') != std::string::npos || e.file.rfind(".rkf") + 4 != e.file.size())
        in.fail("keyframe file '" + e.file + "' is not a .rkf name in the folder");
      e.points = in.integer<std::uint64_t>(w[3], "points");
      e.edits = in.integer<std::uint64_t>(w[4], "edits");
      if (w.size() == 6) {
        in.expect_word(w[5], "none");
      } else {
        in.expect_word(w[5], "reach");
        std::array<std::int64_t, 6> r{};
        for (int a = 0; a < 6; ++a) {
          r[static_cast<std::size_t>(a)] =
              in.integer<std::int64_t>(w[static_cast<std::size_t>(6 + a)], "reach");
          if (r[static_cast<std::size_t>(a)] < 0 || r[static_cast<std::size_t>(a)] >= extent)
            in.fail("reach outside the key range");
        }
        for (int a = 0; a < 3; ++a)
          if (r[static_cast<std::size_t>(a)] > r[static_cast<std::size_t>(a + 3)])
            in.fail("reach with lo > hi");
        e.reach = r;
      }
      s.entries_.push_back(std::move(e));
    }
    in.take("end", 0);
    if (!in.done()) in.fail("lines after 'end'");
    return s;
  }

  const std::string& dir() const { return dir_; }
  double resolution() const { return resolution_; }
  int key_bits() const { return key_bits_; }
  const IntegrationParams& params() const { return params_; }
  const RatingTotals& totals() const { return totals_; }
  std::size_t size() const { return entries_.size(); }
  const RatedKeyframeEntry& entry(std::size_t i) const { return entries_.at(i); }
  std::string path_of(std::size_t i) const {
    return (std::filesystem::path(dir_) / entries_.at(i).file).string();
  }

  /// Keyframe i into `rk` (its kind must be the run's, its counts the index's). No memory for it:
  /// std::bad_alloc, as for the map it goes into (tile mapping halves a group that runs out).
  void load(std::size_t i, RatedKeyframe& rk) const {
    const std::string path = path_of(i);
    const io::detail::FileBuffer buf = io::detail::read_file(path, true);
    decode_rated_keyframe(path, buf.data(), buf.size(), rk);
    const RatedKeyframeEntry& e = entries_[i];
    if (rk.kind != params_.kind || rk.points.size() != e.points || rk.edits.size() != e.edits)
      throw io::Error(path, "does not match rated.txt (kind, points or edits)");
  }

  /// The keyframes whose reach holds a key of `keys` (per-axis lo and hi indices), in order.
  std::vector<std::size_t> reaching(const std::array<std::int64_t, 6>& keys) const {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      const auto& r = entries_[i].reach;
      if (!r) continue;
      bool hit = true;
      for (std::size_t a = 0; a < 3 && hit; ++a)
        hit = (*r)[a] <= keys[a + 3] && (*r)[a + 3] >= keys[a];
      if (hit) out.push_back(i);
    }
    return out;
  }

 private:
  std::string dir_;
  double resolution_ = 0;
  int key_bits_ = 16;
  IntegrationParams params_;
  RatingTotals totals_;
  std::vector<RatedKeyframeEntry> entries_;
};

/// Writes a folder of rated keyframes: add() each keyframe in order (its file is written at
/// once), then finish() writes rated.txt. The folder must exist.
template <class Key>
class RatedStoreWriter {
 public:
  RatedStoreWriter(std::string dir, double resolution) : dir_(std::move(dir)), grid_(resolution) {}

  const Grid<Key>& grid() const { return grid_; }

  /// Keyframe `rk` (the next one) into its file; returns the keys it can update.
  std::optional<KeyBounds<Key>> add(const RatedKeyframe& rk) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.rkf", entries_.size());
    RatedKeyframeEntry e;
    e.file = name;
    e.points = rk.points.size();
    e.edits = rk.edits.size();
    const std::optional<KeyBounds<Key>> reach = keyframe_reach(grid_, rk);
    if (reach)
      e.reach = std::array<std::int64_t, 6>{reach->lo[0], reach->lo[1], reach->lo[2],
                                            reach->hi[0], reach->hi[1], reach->hi[2]};
    io::AtomicFile f((std::filesystem::path(dir_) / name).string());
    f.write(encode_rated_keyframe(rk));
    f.commit();
    entries_.push_back(std::move(e));
    return reach;
  }

  /// rated.txt, after the last keyframe.
  void finish(const IntegrationParams& params, const RatingTotals& totals) {
    using detail::number_text;
    std::string text = "knnocc rated keyframes 1\nresolution " + number_text(grid_.resolution()) +
                       "\nkey_bits " + std::to_string(Key::depth) + "\n" +
                       detail::integration_lines(params);
    text += "totals clouds " + number_text(totals.clouds) + " points " +
            number_text(totals.points) + " nonfinite " + number_text(totals.nonfinite) +
            " out_of_range " + number_text(totals.out_of_range) + " rated " +
            number_text(totals.rated) + " rays " + number_text(totals.rays) + "\n";
    text += "keyframes " + std::to_string(entries_.size()) + "\n";
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      const RatedKeyframeEntry& e = entries_[i];
      text += "k " + std::to_string(i) + " " + e.file + " " + number_text(e.points) + " " +
              number_text(e.edits);
      if (e.reach) {
        text += " reach";
        for (const std::int64_t v : *e.reach) text += " " + std::to_string(v);
      } else {
        text += " none";
      }
      text += "\n";
    }
    text += "end\n";
    io::AtomicFile f((std::filesystem::path(dir_) / "rated.txt").string());
    f.write(text);
    f.commit();
  }

 private:
  std::string dir_;
  Grid<Key> grid_;
  std::vector<RatedKeyframeEntry> entries_;
};

}  // namespace knnocc::tiles
