#pragma once
// The synthetic spinning LiDAR of bench_lidar (and bench_bonxai_memory): an analytic street scene
// (ground plane, box buildings and cars, thin poles) and 64-beam sweeps of it from a moving
// vehicle. Beams that hit nothing within `range` get an end point 5 m beyond it (inserted with
// max_range = range: free space up to the range, no occupied voxel).

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "bench_common.hpp"

namespace knnocc::bench {

struct Box {
  double lo[3], hi[3];
};

// Slab test: distance along the unit direction d from o to the box, or a negative number.
inline double hit_box(const Box& b, const double o[3], const double d[3]) {
  double t0 = 0.0, t1 = 1e30;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return -1.0;
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return -1.0;
  }
  return t0 > 0.0 ? t0 : -1.0;
}

struct Scene {
  std::vector<Box> boxes;

  explicit Scene(unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Buildings along both sides of a 300 m street (y in [-8, 8] is the road).
    for (double x = -40; x < 300; x += 12 + 10 * u(rng)) {
      for (const double side : {-1.0, 1.0}) {
        const double y0 = side * (9 + 4 * u(rng)), depth = 8 + 10 * u(rng);
        const double w = 6 + 6 * u(rng), h = 4 + 12 * u(rng);
        boxes.push_back(
            {{x, std::min(y0, y0 + side * depth), 0}, {x + w, std::max(y0, y0 + side * depth), h}});
      }
    }
    // Parked cars and poles.
    for (double x = -40; x < 300; x += 5 + 15 * u(rng)) {
      const double y = (u(rng) < 0.5 ? -1 : 1) * (5.5 + 1.5 * u(rng));
      boxes.push_back({{x, y - 0.9, 0}, {x + 4.3, y + 0.9, 1.5}});
      const double py = (u(rng) < 0.5 ? -1 : 1) * 8.3;
      boxes.push_back({{x + 2, py - 0.1, 0}, {x + 2.2, py + 0.1, 6}});
    }
  }

  // Range to the first surface along the unit direction d, or a negative number.
  double cast(const double o[3], const double d[3]) const {
    double best = d[2] < 0 ? -o[2] / d[2] : -1.0;  // ground z = 0
    for (const Box& b : boxes) {
      const double t = hit_box(b, o, d);
      if (t > 0 && (best < 0 || t < best)) best = t;
    }
    return best;
  }
};

inline std::vector<Scan> simulate(const Scene& scene, int scans, int beams, int azimuths,
                                  double range, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Scan> out;
  for (int s = 0; s < scans; ++s) {
    Scan scan;
    const double o[3] = {2.0 * s, 0.3 * std::sin(0.3 * s), 1.8};  // 2 m between scans
    scan.origin = {float(o[0]), float(o[1]), float(o[2])};
    for (int b = 0; b < beams; ++b) {
      const double elev = (-24.9 + (2.0 + 24.9) * b / (beams - 1)) * M_PI / 180.0;  // HDL-64
      for (int a = 0; a < azimuths; ++a) {
        const double az = 2 * M_PI * (a + 0.5 * (b % 2)) / azimuths;
        const double d[3] = {std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az),
                             std::sin(elev)};
        double r = scene.cast(o, d);
        if (r < 0 || r > range)
          r = range + 5.0;  // no return: beyond the max range
        else
          r += noise(rng);
        scan.points.push_back(
            {float(o[0] + r * d[0]), float(o[1] + r * d[1]), float(o[2] + r * d[2])});
      }
    }
    out.push_back(std::move(scan));
  }
  return out;
}

}  // namespace knnocc::bench
