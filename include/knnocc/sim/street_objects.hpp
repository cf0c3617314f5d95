// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// StreetObjects: what stands along the simulated drive's streets (sim/street_network.hpp), in a
// uniform 2D grid over xy so that a beam tests only the objects of the cells it crosses.
//
// Every object is one convex shape given by its axis-aligned box: a box, a vertical cylinder in
// it (square footprint) or an ellipsoid in it. Per city block (the land between four roads):
// a 3-5 m sidewalk along its kerbs; buildings along each side, set back 0-6 m behind the
// sidewalk, 10-35 m of frontage, 10-25 m deep, 1-8 storeys (one in ten 9-16), with gaps between
// some of them and courtyards behind; street trees on the sidewalk (trunk cylinder, ellipsoid
// crown) and street-light poles. Per road segment (between two crossings): parked cars along
// both kerbs and moving cars in the outer lanes, which go back and forth along the segment
// (never into a crossing, never in the vehicle's inner lanes). Cars are boxes. The ground is the
// plane z = 0 (not an object).
//
// Only blocks and road segments within `reach` of the route are filled: a beam of at most reach
// metres from the route meets nothing beyond them. Each block and segment draws from its own
// stream of the seed, so the objects near a route do not depend on how long it is.
//
// Thread safety: immutable once built; first_hit() may be called from any number of threads.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "street_network.hpp"

namespace knnocc::sim {

/// What a beam hit (a point's label).
enum class Surface : std::uint8_t { ground, building, trunk, crown, pole, parked_car, moving_car };

enum class ShapeType : std::uint8_t { box, cylinder, ellipsoid };

/// One convex object: a box, or the vertical cylinder or ellipsoid inscribed in that box.
struct Shape {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  ShapeType type = ShapeType::box;
  Surface surface = Surface::building;
};

namespace detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The interval of t where o + t d is within [lo, hi] on every axis (empty: t0 > t1).
inline void slab(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& o,
                 const Eigen::Vector3d& inv, int axes, double& t0, double& t1) {
  for (int a = 0; a < axes; ++a) {
    if (std::isinf(inv[a])) {  // parallel to the slab
      if (o[a] < lo[a] || o[a] > hi[a]) t0 = kInf;
      continue;
    }
    double ta = (lo[a] - o[a]) * inv[a], tb = (hi[a] - o[a]) * inv[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
}

/// Roots of a t^2 + b t + c = 0 narrowing [t0, t1]; no real root: empty.
inline void quadratic(double a, double b, double c, double& t0, double& t1) {
  if (a <= 0) {  // no motion in the quadric's variables: inside or not
    if (c > 0) t0 = kInf;
    return;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) {
    t0 = kInf;
    return;
  }
  const double s = std::sqrt(disc);
  const double q = -0.5 * (b + (b < 0 ? -s : s));  // no cancellation
  double r0 = q / a, r1 = q != 0 ? c / q : r0;
  if (r0 > r1) std::swap(r0, r1);
  t0 = std::max(t0, r0);
  t1 = std::min(t1, r1);
}

}  // namespace detail

/// Where the ray o + t d (t >= 0; inv = 1 / d per axis) enters `s`: t, 0 when o is inside, or
/// +inf when it misses.
inline double ray_entry(const Shape& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                        const Eigen::Vector3d& inv) {
  double t0 = 0, t1 = detail::kInf;
  if (s.type == ShapeType::box) {
    detail::slab(s.lo, s.hi, o, inv, 3, t0, t1);
  } else if (s.type == ShapeType::cylinder) {
    detail::slab(s.lo, s.hi, o, inv, 3, t0, t1);  // its box first: most beams miss it
    if (t0 > t1) return detail::kInf;
    const Eigen::Vector2d c = 0.5 * (s.lo + s.hi).head<2>(), q = o.head<2>() - c;
    const double r = 0.5 * (s.hi.x() - s.lo.x());
    detail::quadratic(d.head<2>().squaredNorm(), 2 * q.dot(d.head<2>()), q.squaredNorm() - r * r,
                      t0, t1);
  } else {
    const Eigen::Vector3d c = 0.5 * (s.lo + s.hi), h = 0.5 * (s.hi - s.lo);
    const Eigen::Vector3d q = (o - c).cwiseQuotient(h), e = d.cwiseQuotient(h);
    detail::quadratic(e.squaredNorm(), 2 * q.dot(e), q.squaredNorm() - 1, t0, t1);
  }
  return t0 <= t1 ? t0 : detail::kInf;
}

/// Whether p lies inside `s` by more than `margin` (for each axis of a box; radially for a
/// cylinder; in the ellipsoid shrunk by margin along each semi-axis).
inline bool contains(const Shape& s, const Eigen::Vector3d& p, double margin = 0) {
  for (int a = 0; a < 3; ++a)
    if (p[a] <= s.lo[a] + margin || p[a] >= s.hi[a] - margin) return false;
  if (s.type == ShapeType::box) return true;
  const Eigen::Vector3d c = 0.5 * (s.lo + s.hi), h = 0.5 * (s.hi - s.lo);
  if (s.type == ShapeType::cylinder) return (p - c).head<2>().norm() < h.x() - margin;
  const Eigen::Vector3d shrunk = (h.array() - margin).max(1e-9).matrix();
  return (p - c).cwiseQuotient(shrunk).squaredNorm() < 1;
}

/// A car driving back and forth along a road segment.
struct MovingCar {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  ///< the lane's start, on the ground
  Eigen::Vector2d dir = Eigen::Vector2d::UnitX();   ///< along the road (an axis)
  double span = 0;                                  ///< drivable length of the lane (m)
  double phase = 0, speed = 0;                      ///< m along the lane at t = 0, m/s
  double length = 4.5, width = 1.8, height = 1.5;

  /// The car at time t (s): a box.
  Shape at(double t) const {
    const double period = 2 * span, d = std::fmod(phase + speed * t, period);
    const double along = 0.5 * length + (span - length) * (d < span ? d : period - d) / span;
    const Eigen::Vector2d c = start + along * dir;
    const Eigen::Vector2d half =
        0.5 * (length * dir.cwiseAbs() + width * Eigen::Vector2d(dir.y(), dir.x()).cwiseAbs());
    Shape s;
    s.lo << c - half, 0.0;
    s.hi << c + half, height;
    s.surface = Surface::moving_car;
    return s;
  }
};

/// A uniform grid of square cells over xy, each listing the shapes whose box overlaps it.
class ShapeGrid {
 public:
  static constexpr double kCell = 8.0;  ///< cell edge (m)

  ShapeGrid() = default;
  /// The grid over `shapes` (indices into it); cells are aligned to multiples of kCell.
  explicit ShapeGrid(const std::vector<Shape>& shapes) {
    if (shapes.empty()) return;
    x0_ = y0_ = std::numeric_limits<std::int64_t>::max();
    std::int64_t x1 = std::numeric_limits<std::int64_t>::min(), y1 = x1;
    for (const Shape& s : shapes) {
      x0_ = std::min(x0_, cell(s.lo.x()));
      y0_ = std::min(y0_, cell(s.lo.y()));
      x1 = std::max(x1, cell(s.hi.x()));
      y1 = std::max(y1, cell(s.hi.y()));
    }
    nx_ = x1 - x0_ + 1;
    ny_ = y1 - y0_ + 1;
    first_.assign(static_cast<std::size_t>(nx_ * ny_ + 1), 0);
    for (int pass = 0; pass < 2; ++pass) {  // count, then fill
      std::vector<std::uint32_t> fill(first_.begin(), first_.end() - 1);
      if (pass == 1) items_.resize(first_.back());
      for (std::size_t k = 0; k < shapes.size(); ++k)
        for (std::int64_t y = cell(shapes[k].lo.y()); y <= cell(shapes[k].hi.y()); ++y)
          for (std::int64_t x = cell(shapes[k].lo.x()); x <= cell(shapes[k].hi.x()); ++x) {
            const std::size_t c = index(x, y);
            if (pass == 0)
              ++first_[c + 1];
            else
              items_[fill[c]++] = static_cast<std::uint32_t>(k);
          }
      if (pass == 0)
        for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
    }
  }

  static std::int64_t cell(double v) { return static_cast<std::int64_t>(std::floor(v / kCell)); }

  /// The shapes listed in cell (x, y) (cell indices as cell() gives them): [begin, end).
  const std::uint32_t* begin(std::int64_t x, std::int64_t y) const {
    return inside(x, y) ? items_.data() + first_[index(x, y)] : nullptr;
  }
  const std::uint32_t* end(std::int64_t x, std::int64_t y) const {
    return inside(x, y) ? items_.data() + first_[index(x, y) + 1] : nullptr;
  }

 private:
  bool inside(std::int64_t x, std::int64_t y) const {
    return x >= x0_ && y >= y0_ && x < x0_ + nx_ && y < y0_ + ny_;
  }
  std::size_t index(std::int64_t x, std::int64_t y) const {
    return static_cast<std::size_t>((y - y0_) * nx_ + (x - x0_));
  }

  std::int64_t x0_ = 0, y0_ = 0, nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> first_;  // per cell, its first item; one more at the end
  std::vector<std::uint32_t> items_;
};

namespace detail {

/// Walks the cells of `ShapeGrid` that the ray o + t d crosses for t in [0, t_max], in order:
/// visit(x, y, t_exit) for each; stops when visit returns true.
template <class Visit>
void walk_cells(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max, Visit&& visit) {
  const double c = ShapeGrid::kCell;
  std::int64_t ix = ShapeGrid::cell(o.x()), iy = ShapeGrid::cell(o.y());
  const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
  // t at the first cell wall crossed on an axis, and between walls (inf: parallel to them).
  const auto first_wall = [c](double p, std::int64_t i, int step, double speed) {
    return speed == 0 ? kInf
                      : std::abs(static_cast<double>(i + (step > 0 ? 1 : 0)) * c - p) / speed;
  };
  const double dx = std::abs(d.x()), dy = std::abs(d.y());
  double tx = first_wall(o.x(), ix, sx, dx), ty = first_wall(o.y(), iy, sy, dy);
  const double step_x = dx == 0 ? kInf : c / dx, step_y = dy == 0 ? kInf : c / dy;
  for (;;) {
    const double t_exit = std::min({tx, ty, t_max});
    if (visit(ix, iy, t_exit) || t_exit >= t_max) return;
    if (tx < ty) {
      ix += sx;
      tx += step_x;
    } else {
      iy += sy;
      ty += step_y;
    }
  }
}

}  // namespace detail

class StreetObjects {
 public:
  /// The objects within `reach` metres of `route` (through `net`, which may grow columns).
  StreetObjects(StreetNetwork& net, const DriveRoute& route, std::uint64_t seed,
                double reach = 100.0) {
    Box2 route_box{route.corners().front(), route.corners().front()};
    for (const auto& c : route.corners()) route_box.grow(c);
    const auto near = [&](const Box2& b) {
      for (std::size_t k = 1; k < route.corners().size(); ++k) {
        Box2 leg{route.corners()[k - 1], route.corners()[k - 1]};
        leg.grow(route.corners()[k]);
        if (leg.distance(b) <= reach) return true;
      }
      return false;
    };
    for (int i = 0; net.column(i).centre <= route_box.hi.x() + reach; ++i) {
      const Road west = net.column(i), east = net.column(i + 1);
      for (int j = 0; j <= StreetNetwork::kRows; ++j) {
        const Road row = net.row(j);
        const Box2 segment{{west.centre + 0.5 * west.width, row.centre - 0.5 * row.width},
                           {east.centre - 0.5 * east.width, row.centre + 0.5 * row.width}};
        if (near(segment)) add_segment(segment, true, stream(seed, 10, i, j));
        if (j == StreetNetwork::kRows) break;
        const Road north = net.row(j + 1);
        const Box2 block{{west.centre + 0.5 * west.width, row.centre + 0.5 * row.width},
                         {east.centre - 0.5 * east.width, north.centre - 0.5 * north.width}};
        if (near(block)) add_block(block, stream(seed, 11, i, j));
        const Box2 cross{{west.centre - 0.5 * west.width, row.centre + 0.5 * row.width},
                         {west.centre + 0.5 * west.width, north.centre - 0.5 * north.width}};
        if (near(cross)) add_segment(cross, false, stream(seed, 12, i, j));
      }
    }
    grid_ = ShapeGrid(shapes_);
  }

  /// The static objects (buildings, trees, poles, parked cars).
  const std::vector<Shape>& shapes() const { return shapes_; }
  const std::vector<MovingCar>& moving_cars() const { return moving_; }
  const ShapeGrid& grid() const { return grid_; }

 private:
  struct Box2 {
    Eigen::Vector2d lo, hi;
    void grow(const Eigen::Vector2d& p) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    double distance(const Box2& b) const {
      const Eigen::Vector2d gap = (b.lo - hi).cwiseMax(lo - b.hi).cwiseMax(0.0);
      return gap.norm();
    }
  };

  static detail::DriveRng stream(std::uint64_t seed, std::uint64_t what, int i, int j) {
    return detail::DriveRng(detail::stream_seed(
        seed, what, static_cast<std::uint64_t>(i) << 32 | static_cast<std::uint32_t>(j)));
  }

  void add(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, ShapeType type, Surface s) {
    shapes_.push_back({lo, hi, type, s});
  }

  // A point `along` metres along side `side` of block `b`, `in` metres inwards from its kerb
  // (sides: 0 south, 1 north along x; 2 west, 3 east along y).
  static Eigen::Vector2d on_side(const Box2& b, int side, double along, double in) {
    switch (side) {
      case 0:
        return {b.lo.x() + along, b.lo.y() + in};
      case 1:
        return {b.lo.x() + along, b.hi.y() - in};
      case 2:
        return {b.lo.x() + in, b.lo.y() + along};
      default:
        return {b.hi.x() - in, b.lo.y() + along};
    }
  }
  // A box on side `side` spanning [a0, a1] along it and [i0, i1] inwards, height z.
  void side_box(const Box2& b, int side, double a0, double a1, double i0, double i1, double z,
                Surface s) {
    const Eigen::Vector2d p = on_side(b, side, a0, i0), q = on_side(b, side, a1, i1);
    add({std::min(p.x(), q.x()), std::min(p.y(), q.y()), 0.0},
        {std::max(p.x(), q.x()), std::max(p.y(), q.y()), z}, ShapeType::box, s);
  }

  void add_block(const Box2& b, detail::DriveRng rng) {
    const double walk = rng.uniform(3, 5), sx = b.hi.x() - b.lo.x(), sy = b.hi.y() - b.lo.y();
    const double setback_max = 6.0;
    const double deep_x = std::min(25.0, 0.5 * (sy - 2 * walk) - setback_max - 1);  // N, S sides
    const double deep_y = std::min(25.0, 0.5 * (sx - 2 * walk) - setback_max - 1);
    for (int side = 0; side < 4; ++side) {
      const bool along_x = side < 2;
      const double length = along_x ? sx : sy;
      // N and S buildings take the corners; W and E ones fill between them.
      const double a0 = along_x ? walk : walk + setback_max + deep_x + 1;
      const double a1 = length - a0, deep = along_x ? deep_x : deep_y;
      for (double a = a0; a < a1 - 6 && deep >= 8;) {
        if (rng.chance(0.3)) {  // a gap: a lot, a passage, a small park
          a += rng.uniform(3, 12);
          continue;
        }
        const double front = std::min(rng.uniform(10, 35), a1 - a);
        if (front < 6) break;
        const double setback = rng.chance(0.5) ? 0.0 : rng.uniform(1, setback_max);
        const int storeys = rng.chance(0.1) ? rng.pick(9, 16) : rng.pick(1, 8);
        const double z = storeys * rng.uniform(3.0, 3.6) + rng.uniform(0, 1.5);
        const double in = walk + setback;
        side_box(b, side, a, a + front, in, in + rng.uniform(std::min(10.0, deep), deep), z,
                 Surface::building);
        a += front + (rng.chance(0.5) ? 0.0 : rng.uniform(1, 4));
      }
      // Street trees and lights along the kerb.
      if (rng.chance(0.75)) {
        const double spacing = rng.uniform(7, 14);
        for (double a = 3 + rng.uniform(0, spacing); a < length - 3; a += spacing) {
          if (rng.chance(0.15)) continue;
          const Eigen::Vector2d p = on_side(b, side, a + rng.uniform(-1, 1), rng.uniform(1.2, 2));
          const double r = rng.uniform(0.12, 0.3), trunk = rng.uniform(2.0, 4.0);
          const double crown_r = rng.uniform(1.5, 3.5), crown_h = rng.uniform(1.5, 4.0);
          const double cz = trunk + 0.6 * crown_h;
          add({p.x() - r, p.y() - r, 0.0}, {p.x() + r, p.y() + r, trunk + 0.3 * crown_h},
              ShapeType::cylinder, Surface::trunk);
          add({p.x() - crown_r, p.y() - crown_r, cz - crown_h},
              {p.x() + crown_r, p.y() + crown_r, cz + crown_h}, ShapeType::ellipsoid,
              Surface::crown);
        }
      }
      const double pole_spacing = rng.uniform(25, 40);
      for (double a = rng.uniform(2, pole_spacing); a < length - 2; a += pole_spacing) {
        const Eigen::Vector2d p = on_side(b, side, a, 0.5);
        const double h = rng.uniform(6, 9);
        add({p.x() - 0.1, p.y() - 0.1, 0.0}, {p.x() + 0.1, p.y() + 0.1, h}, ShapeType::cylinder,
            Surface::pole);
      }
    }
  }

  // A road segment between two crossings: box `s` from kerb to kerb, along x or along y.
  void add_segment(const Box2& s, bool along_x, detail::DriveRng rng) {
    const int a = along_x ? 0 : 1, c = 1 - a;  // along, across
    const double length = s.hi[a] - s.lo[a], width = s.hi[c] - s.lo[c];
    if (length < 12) return;
    const double centre = 0.5 * (s.lo[c] + s.hi[c]);
    const double lane = 0.5 * (0.5 * width - Road::kParking);  // lane width
    const auto car = [&](double& l, double& w, double& h) {
      const bool van = rng.chance(0.1);
      l = van ? rng.uniform(5.0, 6.0) : rng.uniform(3.9, 5.0);
      w = van ? rng.uniform(1.9, 2.1) : rng.uniform(1.7, 1.9);
      h = van ? rng.uniform(2.0, 2.5) : rng.uniform(1.4, 1.7);
    };
    for (int kerb = -1; kerb <= 1; kerb += 2) {
      const double across = centre + kerb * (0.5 * width - 1.1);
      for (double u = s.lo[a] + 4; u < s.hi[a] - 4;) {
        if (!rng.chance(0.65)) {
          u += rng.uniform(3, 8);
          continue;
        }
        double l = 0, w = 0, h = 0;
        car(l, w, h);
        if (u + l > s.hi[a] - 4) break;
        Eigen::Vector3d lo, hi;
        lo[a] = u;
        hi[a] = u + l;
        lo[c] = across - 0.5 * w;
        hi[c] = across + 0.5 * w;
        lo.z() = 0;
        hi.z() = h;
        add(lo, hi, ShapeType::box, Surface::parked_car);
        u += l + rng.uniform(0.6, 2.0);
      }
      // Moving cars in the outer lane on this side (its traffic direction does not matter).
      const int cars = static_cast<int>(length / 60.0 * rng.uniform(0, 1.5));
      for (int k = 0; k < cars; ++k) {
        MovingCar m;
        m.start[a] = s.lo[a] + 4;
        m.start[c] = centre + kerb * 1.5 * lane;
        m.dir = along_x ? Eigen::Vector2d::UnitX() : Eigen::Vector2d::UnitY();
        m.span = length - 8;
        car(m.length, m.width, m.height);
        if (m.span <= m.length) break;
        m.phase = rng.uniform(0, 2 * m.span);
        m.speed = rng.uniform(6, 14);
        moving_.push_back(m);
      }
    }
  }

  std::vector<Shape> shapes_;
  std::vector<MovingCar> moving_;
  ShapeGrid grid_;
};

}  // namespace knnocc::sim
