// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Reference: the ground-truth shapes of a scene, as in the paper's experiment (section 4.1): the
// foliage an ellipsoid, the pot a cuboid, and the ground plane. Solids are axis-aligned.
//
// Text format (`reference.txt`, written by `knnocc sim`, read by `knnocc eval`), one shape per
// line, '#' starts a comment:
//   ground Z                      the ground plane z = Z (at most one line)
//   ellipsoid CX CY CZ AX AY AZ   centre and semi-axes (> 0)
//   cuboid X0 Y0 Z0 X1 Y1 Z1      opposite corners, X0 < X1, Y0 < Y1, Z0 < Z1
//
// Thread safety: const queries (relation, distance, evaluate) may run concurrently.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "../core/point3.hpp"
#include "../io/atomic_file.hpp"
#include "../io/detail/file_text.hpp"
#include "../io/error.hpp"

namespace knnocc::eval {

struct Ellipsoid {
  Point3d centre, semi_axes;
};
struct Cuboid {
  Point3d lo, hi;
};

/// How an axis-aligned box (a voxel) lies relative to the reference solids.
enum class BoxRelation { outside, boundary, inside };

namespace detail {

// min and max of ((x - c) / a)^2 over x in [lo, hi].
inline void axis_range(double lo, double hi, double c, double a, double& mn, double& mx) {
  const double l = (lo - c) / a, h = (hi - c) / a;
  mx = std::max(l * l, h * h);
  mn = (l <= 0 && h >= 0) ? 0.0 : std::min(l * l, h * h);
}

// Distance from q to the surface of the ellipsoid x^2/a^2 + ... = 1 for q outside it (q in the
// ellipsoid's frame): the closest point is x_i = a_i^2 q_i / (a_i^2 + t) for the root t > 0 of
// sum (a_i q_i / (a_i^2 + t))^2 = 1, found by bisection (the sum falls monotonically in t).
inline double outside_distance(const double (&q)[3], const double (&a)[3]) {
  auto f = [&](double t) {
    double s = 0;
    for (int i = 0; i < 3; ++i) {
      const double v = a[i] * q[i] / (a[i] * a[i] + t);
      s += v * v;
    }
    return s - 1.0;
  };
  double lo = 0, hi = 1;
  while (f(hi) > 0) hi *= 2;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) > 0 ? lo : hi) = mid;
  }
  const double t = 0.5 * (lo + hi);
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const double x = a[i] * a[i] * q[i] / (a[i] * a[i] + t);
    d2 += (q[i] - x) * (q[i] - x);
  }
  return std::sqrt(d2);
}

}  // namespace detail

class Reference {
 public:
  std::vector<Ellipsoid> ellipsoids;
  std::vector<Cuboid> cuboids;
  bool has_ground = false;
  double ground_z = 0.0;

  /// Is the point inside (or on) a solid?
  bool contains(const Point3d& p) const { return distance(p) == 0.0; }

  /// Euclidean distance from p to the nearest solid (0 inside); +inf without solids.
  double distance(const Point3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    const double q[3] = {p.x, p.y, p.z};
    for (const Ellipsoid& e : ellipsoids) {
      const double y[3] = {q[0] - e.centre.x, q[1] - e.centre.y, q[2] - e.centre.z};
      const double a[3] = {e.semi_axes.x, e.semi_axes.y, e.semi_axes.z};
      double f = 0;
      for (int i = 0; i < 3; ++i) f += (y[i] / a[i]) * (y[i] / a[i]);
      best = std::min(best, f <= 1.0 ? 0.0 : detail::outside_distance(y, a));
    }
    for (const Cuboid& c : cuboids) {
      const double lo[3] = {c.lo.x, c.lo.y, c.lo.z}, hi[3] = {c.hi.x, c.hi.y, c.hi.z};
      double d2 = 0;
      for (int i = 0; i < 3; ++i) {
        const double d = std::max({lo[i] - q[i], 0.0, q[i] - hi[i]});
        d2 += d * d;
      }
      best = std::min(best, std::sqrt(d2));
    }
    return best;
  }

  /// The closed box [lo, hi] lies strictly inside a solid (inside), meets the surface of a solid
  /// (boundary), or neither (outside). Exact for these convex solids: the ellipsoid's function is
  /// separable, so its min and max over a box are sums of per-axis ones.
  BoxRelation relation(const Point3d& lo, const Point3d& hi) const {
    bool meets = false;
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    for (const Ellipsoid& e : ellipsoids) {
      const double c[3] = {e.centre.x, e.centre.y, e.centre.z};
      const double a[3] = {e.semi_axes.x, e.semi_axes.y, e.semi_axes.z};
      double mn = 0, mx = 0;
      for (int i = 0; i < 3; ++i) {
        double a_mn, a_mx;
        detail::axis_range(l[i], h[i], c[i], a[i], a_mn, a_mx);
        mn += a_mn;
        mx += a_mx;
      }
      if (mx < 1.0) return BoxRelation::inside;
      meets = meets || mn <= 1.0;
    }
    for (const Cuboid& cb : cuboids) {
      const double c0[3] = {cb.lo.x, cb.lo.y, cb.lo.z}, c1[3] = {cb.hi.x, cb.hi.y, cb.hi.z};
      bool in = true, touch = true;
      for (int i = 0; i < 3; ++i) {
        in = in && l[i] > c0[i] && h[i] < c1[i];
        touch = touch && l[i] <= c1[i] && h[i] >= c0[i];
      }
      if (in) return BoxRelation::inside;
      meets = meets || touch;
    }
    return meets ? BoxRelation::boundary : BoxRelation::outside;
  }

  /// Bounding box of the solids grown by `margin` (lo, hi); empty reference: lo > hi.
  void bounds(double margin, Point3d& lo, Point3d& hi) const {
    const double inf = std::numeric_limits<double>::infinity();
    lo = {inf, inf, inf};
    hi = {-inf, -inf, -inf};
    auto grow = [&](const Point3d& a, const Point3d& b) {
      lo = {std::min(lo.x, a.x - margin), std::min(lo.y, a.y - margin),
            std::min(lo.z, a.z - margin)};
      hi = {std::max(hi.x, b.x + margin), std::max(hi.y, b.y + margin),
            std::max(hi.z, b.z + margin)};
    };
    for (const Ellipsoid& e : ellipsoids)
      grow({e.centre.x - e.semi_axes.x, e.centre.y - e.semi_axes.y, e.centre.z - e.semi_axes.z},
           {e.centre.x + e.semi_axes.x, e.centre.y + e.semi_axes.y, e.centre.z + e.semi_axes.z});
    for (const Cuboid& c : cuboids) grow(c.lo, c.hi);
  }
};

/// Writes the text format above (atomically).
inline void write_reference(const std::string& path, const Reference& ref) {
  std::string text =
      "# knnocc reference scene: ground z | ellipsoid centre semi-axes | cuboid lo hi\n";
  char line[512];
  if (ref.has_ground) {
    std::snprintf(line, sizeof line, "ground %.17g\n", ref.ground_z);
    text += line;
  }
  for (const Ellipsoid& e : ref.ellipsoids) {
    std::snprintf(line, sizeof line, "ellipsoid %.17g %.17g %.17g %.17g %.17g %.17g\n", e.centre.x,
                  e.centre.y, e.centre.z, e.semi_axes.x, e.semi_axes.y, e.semi_axes.z);
    text += line;
  }
  for (const Cuboid& c : ref.cuboids) {
    std::snprintf(line, sizeof line, "cuboid %.17g %.17g %.17g %.17g %.17g %.17g\n", c.lo.x, c.lo.y,
                  c.lo.z, c.hi.x, c.hi.y, c.hi.z);
    text += line;
  }
  io::AtomicFile out(path);
  out.write(text);
  out.commit();
}

/// Reads the text format; io::Error naming the file, line and problem on anything else.
inline Reference read_reference(const std::string& path) {
  const io::detail::FileBuffer buf = io::detail::read_file(path);
  Reference ref;
  io::detail::for_each_line(
      buf.data(), buf.end(), [&](std::size_t n, const char* b, const char* e) {
        const std::string at = "line " + std::to_string(n) + ": ";
        while (b < e && (*b == ' ' || *b == '\t')) ++b;
        const char* w = b;
        while (w < e && *w != ' ' && *w != '\t' && *w != '#' && *w != '\r') ++w;
        const std::string word(b, w);
        if (word.empty()) return;  // blank or comment
        double v[7];
        const std::size_t got = io::detail::scan_line_numbers(path, n, w, e, v, 7, true);
        for (std::size_t i = 0; i < got; ++i)
          if (!std::isfinite(v[i])) throw io::Error(path, at + "non-finite number");
        auto expect = [&](std::size_t count) {
          if (got != count)
            throw io::Error(path, at + "'" + word + "' expects " + std::to_string(count) +
                                      " numbers, found " +
                                      (got > count ? "more" : std::to_string(got)));
        };
        if (word == "ground") {
          expect(1);
          if (ref.has_ground) throw io::Error(path, at + "a second ground line");
          ref.has_ground = true;
          ref.ground_z = v[0];
        } else if (word == "ellipsoid") {
          expect(6);
          if (!(v[3] > 0 && v[4] > 0 && v[5] > 0))
            throw io::Error(path, at + "ellipsoid semi-axes must be > 0");
          ref.ellipsoids.push_back({{v[0], v[1], v[2]}, {v[3], v[4], v[5]}});
        } else if (word == "cuboid") {
          expect(6);
          if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5]))
            throw io::Error(path, at + "cuboid corners must satisfy x0 < x1, y0 < y1, z0 < z1");
          ref.cuboids.push_back({{v[0], v[1], v[2]}, {v[3], v[4], v[5]}});
        } else {
          throw io::Error(path, at + "unknown shape '" + word + "' (ground, ellipsoid or cuboid)");
        }
      });
  if (ref.ellipsoids.empty() && ref.cuboids.empty())
    throw io::Error(path, "no ellipsoid or cuboid in the reference");
  return ref;
}

}  // namespace knnocc::eval
