// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// StreetNetwork and DriveRoute: the streets of the simulated drive (sim/drive_scene.hpp) and the
// vehicle's path through them, without any object or beam, so a route of any length costs
// microseconds.
//
// The network is a grid of city blocks: kRows blocks north-south between kRows + 1 east-west roads
// (along x), and as many north-south roads (along y) as the route needs eastwards. Block sides are
// uniform in [60, 160] m, road widths (kerb to kerb) in [20, 30] m. Each road has a 2.2 m parking
// strip along each kerb and two lanes each way in between; the vehicle keeps to the inner lane of
// its direction (right-hand traffic).
//
// The route starts at the third north-south road, on the middle east-west road, heading east, and
// is planned one leg at a time: east for 2-5 blocks, then, while its eastward progress is at least
// 60 % of its length, sometimes north or south for 1-3 blocks (never onto an outer road) and east
// again. It never turns west, so it visits no street twice, and it reaches far east: a route of L
// metres ends at least 0.6 L minus one north-south leg from its start along x. Corners are arcs
// of kTurnRadius. World coordinates put the start at the origin.
//
// Everything is drawn from the seed through separate streams (the columns, the rows, the route),
// each consumed in order, so a shorter route of the same seed is a prefix of a longer one.
// Deterministic for a seed: own splitmix64 variates, no standard-library distribution.
//
// Thread safety: StreetNetwork grows its columns on demand (column()), so one per thread while
// a route is planned; a built DriveRoute is immutable.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "../core/config.hpp"

namespace knnocc::sim {

namespace detail {

/// splitmix64: a small, fast, well-mixed generator whose stream depends on nothing but its seed.
class DriveRng {
 public:
  explicit DriveRng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// An integer in [lo, hi].
  int pick(int lo, int hi) {
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }
  bool chance(double p) { return uniform() < p; }

 private:
  std::uint64_t s_;
};

/// A seed for stream `what` of `seed` (and an index within it): independent streams.
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t what, std::uint64_t index = 0) {
  DriveRng r(seed ^ (what * 0xD1B54A32D192ED03ull));
  r.next();
  DriveRng s(r.next() ^ (index * 0x9E3779B97F4A7C15ull));
  return s.next();
}

}  // namespace detail

/// One road: its centre line (x of a north-south road, y of an east-west one) and width.
struct Road {
  double centre = 0;
  double width = 0;
  /// The vehicle's lane centre, from the road's centre line (inner lane of two each way).
  double lane_offset() const { return 0.25 * (0.5 * width - kParking); }
  static constexpr double kParking = 2.2;  ///< parking strip along each kerb (m)
};

class StreetNetwork {
 public:
  static constexpr int kRows = 12;        ///< blocks north-south
  static constexpr int kStartColumn = 2;  ///< the route starts on this north-south road
  static constexpr int kStartRow = kRows / 2;

  explicit StreetNetwork(std::uint64_t seed) : columns_rng_(detail::stream_seed(seed, 1)) {
    detail::DriveRng rows(detail::stream_seed(seed, 2));
    for (int j = 0; j <= kRows; ++j) {
      const double w = rows.uniform(20, 30);
      const double y =
          j == 0 ? 0.0
                 : rows_.back().centre + 0.5 * rows_.back().width + rows.uniform(60, 160) + 0.5 * w;
      rows_.push_back({y, w});
    }
    // World coordinates: the start (the vehicle's lane on the start row) at the origin.
    const Road& start_row = rows_[kStartRow];
    const double y0 = start_row.centre - start_row.lane_offset();
    for (Road& r : rows_) r.centre -= y0;
    grow(kStartColumn);
    x0_ = columns_[kStartColumn].centre;
  }

  /// East-west road j (along x, at y = centre), j in [0, kRows].
  Road row(int j) const { return rows_.at(static_cast<std::size_t>(j)); }
  /// North-south road i (along y, at x = centre), i >= 0; made on first use.
  Road column(int i) {
    grow(i);
    Road r = columns_[static_cast<std::size_t>(i)];
    r.centre -= x0_;
    return r;
  }
  /// The north-south roads made so far.
  int columns() const { return static_cast<int>(columns_.size()); }

 private:
  void grow(int i) {
    while (static_cast<int>(columns_.size()) <= i) {
      const double w = columns_rng_.uniform(20, 30);
      const double x = columns_.empty() ? 0.0
                                        : columns_.back().centre + 0.5 * columns_.back().width +
                                              columns_rng_.uniform(60, 160) + 0.5 * w;
      columns_.push_back({x, w});
    }
  }

  std::vector<Road> rows_, columns_;  // columns_ before the shift by x0_
  detail::DriveRng columns_rng_;
  double x0_ = 0;
};

/// The vehicle's path: straight legs along lanes joined by quarter circles, by arc length.
class DriveRoute {
 public:
  static constexpr double kTurnRadius = 9.0;  ///< corner arcs (m)

  /// Planned this far past the length asked for, so that the path up to that length is the same
  /// whatever length was asked for (the last corner's rounding starts before it).
  static constexpr double kMargin = 30.0;

  /// A route of at least `length` metres through `net` (which grows the columns it needs).
  DriveRoute(StreetNetwork& net, double length, std::uint64_t seed) {
    if (!(length >= 0 && length <= 1e6))
      knnocc::detail::invalid_argument("route length must be in [0, 1e6] m");
    plan(net, length + kMargin, detail::DriveRng(detail::stream_seed(seed, 3)));
    build_pieces();
  }

  /// Total length (m), at least the length asked for plus kMargin.
  double length() const { return length_; }
  /// The corners: start, every turn (before rounding), end.
  const std::vector<Eigen::Vector2d>& corners() const { return corners_; }

  /// Position on the ground and unit heading at arc length s (clamped to the route).
  void at(double s, Eigen::Vector2d& position, Eigen::Vector2d& heading) const {
    s = std::clamp(s, 0.0, length_);
    auto it = std::upper_bound(starts_.begin(), starts_.end(), s);
    const std::size_t k = static_cast<std::size_t>(
        std::max<std::ptrdiff_t>(0, std::distance(starts_.begin(), it) - 1));
    const Piece& p = pieces_[k];
    const double t = std::min(s - starts_[k], p.length);
    if (p.radius == 0) {
      position = p.a + p.u * t;
      heading = p.u;
      return;
    }
    const double th = t / p.radius;  // centre + R (-u_out cos th + u_in sin th)
    position = p.a + p.radius * (-p.v * std::cos(th) + p.u * std::sin(th));
    heading = p.u * std::cos(th) + p.v * std::sin(th);
  }

 private:
  struct Piece {
    Eigen::Vector2d a, u, v;  // line: start, direction; arc: centre, incoming, outgoing
    double radius = 0;        // 0: a line
    double length = 0;
  };
  enum Dir { east, north, south };

  // The lane line's coordinate: y on an east-west road heading east, x on a north-south road.
  static double lane(const Road& r, Dir d) {
    return d == east ? r.centre - r.lane_offset()
                     : r.centre + (d == north ? r.lane_offset() : -r.lane_offset());
  }

  void plan(StreetNetwork& net, double target, detail::DriveRng rng) {
    int i = StreetNetwork::kStartColumn, j = StreetNetwork::kStartRow;
    Dir dir = east;
    Eigen::Vector2d at(net.column(i).centre, lane(net.row(j), east));
    corners_.push_back(at);
    double length = 0;
    const double turn_saving = (2.0 - M_PI / 2) * kTurnRadius;  // a rounded corner's shortcut
    do {
      if (dir == east) {
        i += rng.pick(2, 5);
        const double x_road = net.column(i).centre;
        length += x_road - at.x();  // up to the crossing's centre line
        at.x() = x_road;
        const bool far_enough = at.x() - corners_.front().x() >= 0.6 * length;
        if (!far_enough || length >= target || !rng.chance(0.6)) continue;
        const bool can_north = j<StreetNetwork::kRows - 1, can_south = j> 1;
        dir = can_north && (!can_south || rng.chance(0.5)) ? north : south;
        at.x() = lane(net.column(i), dir);
        length += at.x() - x_road - turn_saving;
      } else {
        const int room = dir == north ? StreetNetwork::kRows - 1 - j : j - 1;
        j += (dir == north ? 1 : -1) * rng.pick(1, std::max(1, std::min(3, room)));
        const double y = lane(net.row(j), east);
        length += std::abs(y - at.y()) - turn_saving;
        at.y() = y;
        dir = east;
      }
      corners_.push_back(at);
    } while (length < target);
    if (at != corners_.back()) corners_.push_back(at);
  }

  void build_pieces() {
    const double R = kTurnRadius;
    Eigen::Vector2d from = corners_.front();
    for (std::size_t k = 1; k < corners_.size(); ++k) {
      const Eigen::Vector2d c = corners_[k];
      const Eigen::Vector2d u = (c - corners_[k - 1]).normalized();
      const bool turn = k + 1 < corners_.size();
      const Eigen::Vector2d to = turn ? Eigen::Vector2d(c - R * u) : c;
      add({from, u, u, 0.0, (to - from).norm()});
      if (turn) {
        const Eigen::Vector2d v = (corners_[k + 1] - c).normalized();
        add({c - R * u + R * v, u, v, R, 0.5 * M_PI * R});
        from = c + R * v;
      }
    }
    if (pieces_.empty()) add({from, Eigen::Vector2d(1, 0), Eigen::Vector2d(1, 0), 0.0, 0.0});
  }
  void add(const Piece& p) {
    starts_.push_back(length_);
    pieces_.push_back(p);
    length_ += p.length;
  }

  std::vector<Eigen::Vector2d> corners_;
  std::vector<Piece> pieces_;
  std::vector<double> starts_;
  double length_ = 0;
};

}  // namespace knnocc::sim
