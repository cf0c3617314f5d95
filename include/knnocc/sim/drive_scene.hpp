// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// DriveScene: a long simulated LiDAR drive through a city, for maps larger than one process
// (`knnocc sim --scene drive`, docs/drive_scene.md).
//
// A vehicle drives a route through a grid of city blocks (sim/street_network.hpp) lined with
// buildings, street trees, poles, parked and moving cars (sim/street_objects.hpp) on the ground
// plane z = 0. A spinning LiDAR at 1.73 m takes a scan every `spacing` metres of road: `beams`
// lasers in an HDL-64E-like vertical pattern (the upper half of the beams evenly from +2.0 to
// -8.33 degrees, the lower half from -8.83 to -24.8), `columns` firings per revolution, each beam
// cast to the first surface (a uniform grid over xy: a beam tests the objects of the cells it
// crosses). A beam that meets nothing within max_range, or something closer than min_range, gives
// no point, as a real sensor returns nothing. Each scan is taken at one instant (no motion
// distortion); the vehicle's body rolls and pitches by up to 0.5 degrees.
//
// Noise, calibrated on the one real laser scan at hand, ../shared/data/octomap_fr079/scan.dat
// (FR-079: a SICK line scanner tilted to scan in 3D, indoors, ranges 0.5-29 m, 491 scan lines;
// measured by the test "drive scene: calibration on the real scan" in tests/test_drive_scene.cpp,
// `ctest --test-dir build -R calibration -V`, which prints the figures and fails if the
// constants below drift from them):
//   range noise  kCalibratedRangeNoise = 5.9 mm (1 sd, along the beam): the median plane-fit
//                residual of sim/plane_noise.hpp over 4,936 patches facing the sensor; per range
//                bin 5.2 mm (4-8 m), 7.4 mm (8-16 m), 18 mm (16-32 m, where a patch spans half a
//                metre of a real wall). With patches of radius 1 % of the range it is 5.2 mm, with
//                larger ones it grows (2 %: 6.8, 3 %: 10.6, 5 %: 21.4 mm): real surfaces are not
//                planes at that scale. A second estimator, each point's distance from the chord
//                of its two neighbours in its scan line, gives 5.9, 7.1 and 7.4 mm at 0.5-2, 2-4
//                and 4-8 m. The simulator draws a normal range error of this sd for every
//                return, the same at every range.
//   dropouts     kCalibratedDropout = 0.336 % of the beams: scan.dat's lines hold 180 or 181
//                points in a pattern repeating every 8 lines; 297 of the 88,503 points that
//                pattern predicts are missing (0.75 % if every line should hold 181). Two thirds
//                are in two stretches of the scan (glass, dark surfaces or openings, likely);
//                the simulator drops that fraction of its returns independently at random.
// What could not be calibrated: no outdoor or spinning-LiDAR data is available, so the noise is
// the indoor line scanner's (an HDL-64E's datasheet gives < 2 cm); its growth with range beyond
// about 16 m, returns from glass, mixed pixels at edges, intensity, and the city's statistics
// (block, road, building and tree sizes are typical values chosen by hand, not measured).
//
// Deterministic per seed (own splitmix64 streams, no standard-library distribution; libm's
// trigonometry may round differently elsewhere). The route, the objects near it and each scan's
// noise come from separate streams, so a drive of N scans is the first N scans of a longer one
// with the same seed and spacing, and scan(i) needs no other scan.
//
// Thread safety: immutable once built; scan() may be called from any number of threads.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../io/cloud.hpp"
#include "../io/trajectory.hpp"
#include "street_network.hpp"
#include "street_objects.hpp"

namespace knnocc::sim {

/// Range noise (1 sd, m) measured on scan.dat (see the top of this file).
inline constexpr double kCalibratedRangeNoise = 0.0059;
/// Fraction of returns missing in scan.dat (see the top of this file).
inline constexpr double kCalibratedDropout = 0.00336;

struct DriveSceneParams {
  std::uint64_t seed = 1;
  std::size_t scans = 2100;  ///< 8,396 m of road at the default spacing
  double spacing = 4.0;      ///< metres of road between scans
  int columns = 1800;        ///< firings per revolution (0.2 degrees)
  int beams = 64;
  double sensor_height = 1.73;  ///< m above the ground
  double max_range = 80.0;      ///< m
  double min_range = 0.9;       ///< m
  double range_noise = kCalibratedRangeNoise;
  double dropout = kCalibratedDropout;
  double speed = 10.0;  ///< m/s: the scans' stamps, and where the moving cars are

  /// Road between the first and the last scan (m).
  double route_length() const { return static_cast<double>(scans - 1) * spacing; }

  void validate() const {
    auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };  // NaN fails
    if (scans < 1 || scans > 1000000)
      knnocc::detail::invalid_argument("scans must be in [1, 1000000]");
    if (!in(spacing, 0.01, 1000))
      knnocc::detail::invalid_argument("spacing must be in [0.01, 1000] m");
    if (!(route_length() <= 200000))
      knnocc::detail::invalid_argument("scans * spacing must be at most 200 km of road");
    if (columns < 1 || columns > 100000 || beams < 1 || beams > 1024)
      knnocc::detail::invalid_argument("columns must be in [1, 100000], beams in [1, 1024]");
    if (!in(sensor_height, 0.1, 100) || !in(max_range, 1, 1000) || !in(min_range, 0, max_range))
      knnocc::detail::invalid_argument(
          "sensor_height in [0.1, 100] m, max_range in [1, 1000] m, min_range in [0, max_range]");
    if (!in(range_noise, 0, 1) || !(dropout >= 0 && dropout < 1) || !in(speed, 0.1, 100))
      knnocc::detail::invalid_argument(
          "range_noise in [0, 1] m, dropout in [0, 1), speed in [0.1, 100] m/s");
  }
};

/// One scan: its pose and its points, with what each point hit and how many beams gave none.
struct DriveScan {
  io::Pose pose;                ///< sensor to world (stamp: seconds since the start)
  io::Cloud cloud;              ///< sensor frame (x forward, y left, z up), beam by beam
  std::vector<Surface> labels;  ///< per point
  std::size_t beams = 0;        ///< beams cast: beams x columns
  std::size_t no_return = 0;    ///< nothing between min_range and max_range
  std::size_t dropped = 0;      ///< a surface, but no point (dropout; noise out of range)
};

/// The lasers' elevations (radians), top first: the HDL-64E-like pattern of the top of this file.
inline std::vector<double> lidar_elevations(int beams) {
  std::vector<double> e;
  const int upper = (beams + 1) / 2, lower = beams - upper;
  const auto spread = [&e](int n, double top, double bottom) {
    for (int k = 0; k < n; ++k)
      e.push_back((n == 1 ? top : top + (bottom - top) * k / (n - 1)) * M_PI / 180.0);
  };
  spread(upper, 2.0, -8.33);
  spread(lower, -8.83, -24.8);
  return e;
}

namespace detail {

/// The vehicle's pose on `route` at scan i: the route's position and heading, the sensor's
/// height, the body's roll and pitch (slow sines of the distance, phases from the seed).
inline io::Pose drive_pose(const DriveRoute& route, const DriveSceneParams& p, std::size_t i) {
  DriveRng rng(stream_seed(p.seed, 4));
  const double roll_phase = rng.uniform(0, 2 * M_PI), pitch_phase = rng.uniform(0, 2 * M_PI);
  const double s = static_cast<double>(i) * p.spacing, amplitude = 0.5 * M_PI / 180.0;
  Eigen::Vector2d at, heading;
  route.at(s, at, heading);
  const double roll = amplitude * std::sin(2 * M_PI * s / 31.0 + roll_phase);
  const double pitch = amplitude * std::sin(2 * M_PI * s / 47.0 + pitch_phase);
  io::Pose pose;
  pose.stamp = s / p.speed;
  pose.t = Eigen::Vector3d(at.x(), at.y(), p.sensor_height);
  pose.q = Eigen::AngleAxisd(std::atan2(heading.y(), heading.x()), Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  return pose;
}

}  // namespace detail

/// The poses of a drive (sensor to world), without its objects or beams: cheap at any length.
inline std::vector<io::Pose> drive_poses(const DriveSceneParams& p) {
  p.validate();
  StreetNetwork net(p.seed);
  const DriveRoute route(net, p.route_length(), p.seed);
  std::vector<io::Pose> poses;
  for (std::size_t i = 0; i < p.scans; ++i) poses.push_back(detail::drive_pose(route, p, i));
  return poses;
}

class DriveScene {
 public:
  explicit DriveScene(const DriveSceneParams& p = {})
      : p_(validated(p)),
        net_(p.seed),
        route_(net_, p.route_length(), p.seed),
        objects_(net_, route_, p.seed, p.max_range + 20.0) {
    for (double e : lidar_elevations(p.beams)) {
      sin_el_.push_back(std::sin(e));
      cos_el_.push_back(std::cos(e));
    }
    for (int c = 0; c < p.columns; ++c) {
      const double a = 2 * M_PI * c / p.columns;
      cos_az_.push_back(std::cos(a));
      sin_az_.push_back(std::sin(a));
    }
  }

  const DriveSceneParams& params() const { return p_; }
  const DriveRoute& route() const { return route_; }
  const StreetObjects& objects() const { return objects_; }
  std::size_t size() const { return p_.scans; }

  /// Sensor to world at scan i.
  io::Pose pose(std::size_t i) const { return detail::drive_pose(route_, p_, i); }

  /// Scan i: every beam cast from pose(i) at the moving cars' positions at its stamp.
  DriveScan scan(std::size_t i) const {
    DriveScan out;
    out.pose = pose(i);
    const Eigen::Matrix3d R = out.pose.q.toRotationMatrix();
    const Eigen::Vector3d o = out.pose.t;
    std::vector<Shape> movers;
    for (const MovingCar& m : objects_.moving_cars()) {
      const Shape s = m.at(out.pose.stamp);
      const Eigen::Vector2d c = 0.5 * (s.lo + s.hi).head<2>();
      if ((c - o.head<2>()).norm() < p_.max_range + 10) movers.push_back(s);
    }
    const ShapeGrid mover_grid(movers);
    detail::DriveRng rng(detail::stream_seed(p_.seed, 5, i));
    out.beams = sin_el_.size() * cos_az_.size();
    out.cloud.points.reserve(out.beams);
    out.labels.reserve(out.beams);
    for (std::size_t b = 0; b < sin_el_.size(); ++b) {
      for (std::size_t c = 0; c < cos_az_.size(); ++c) {
        const Eigen::Vector3d ds(cos_el_[b] * cos_az_[c], cos_el_[b] * sin_az_[c], sin_el_[b]);
        Surface what = Surface::ground;
        const double t = first_hit(o, R * ds, movers, mover_grid, what);
        if (!(t >= p_.min_range && t <= p_.max_range)) {
          ++out.no_return;
          continue;
        }
        const double u = rng.uniform(), r = t + p_.range_noise * normal(rng);
        if (u < p_.dropout || r < p_.min_range || r > p_.max_range) {
          ++out.dropped;
          continue;
        }
        out.cloud.points.push_back({static_cast<float>(r * ds.x()), static_cast<float>(r * ds.y()),
                                    static_cast<float>(r * ds.z())});
        out.labels.push_back(what);
      }
    }
    return out;
  }

 private:
  static const DriveSceneParams& validated(const DriveSceneParams& p) {
    p.validate();
    return p;
  }
  // A standard normal variate (Box-Muller; one of the pair).
  static double normal(detail::DriveRng& rng) {
    const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

  // The distance to the first surface along o + t d (d a unit vector), +inf beyond max_range.
  double first_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                   const std::vector<Shape>& movers, const ShapeGrid& mover_grid,
                   Surface& what) const {
    double best = detail::kInf;
    if (d.z() < 0) best = -o.z() / d.z();  // the ground
    const double limit = std::min(best, p_.max_range);
    const Eigen::Vector3d inv = d.cwiseInverse();
    const auto test = [&](const std::vector<Shape>& shapes, const std::uint32_t* k,
                          const std::uint32_t* end) {
      for (; k != end; ++k) {
        const double t = ray_entry(shapes[*k], o, d, inv);
        if (t < best) {
          best = t;
          what = shapes[*k].surface;
        }
      }
    };
    const ShapeGrid& grid = objects_.grid();
    detail::walk_cells(o, d, limit, [&](std::int64_t x, std::int64_t y, double t_exit) {
      test(objects_.shapes(), grid.begin(x, y), grid.end(x, y));
      test(movers, mover_grid.begin(x, y), mover_grid.end(x, y));
      return best <= t_exit;
    });
    return best <= p_.max_range ? best : detail::kInf;
  }

  DriveSceneParams p_;
  StreetNetwork net_;
  DriveRoute route_;
  StreetObjects objects_;
  std::vector<double> sin_el_, cos_el_, cos_az_, sin_az_;
};

}  // namespace knnocc::sim
