// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// TreeScene: a simulation of the paper's experiment (section 4.1): a stereo camera circling a
// potted tree at 3.5 m, visual-SLAM style sparse feature points with persistent map-point ids.
//
// Scene: foliage = ellipsoid, pot (grass included) = cuboid on the ground plane z = 0, textured
// ground around them; the same shapes are the evaluation reference (eval/reference.hpp).
// Features: fixed sites on the surfaces (foliage sites sit up to 5 cm under the ellipsoid: leaves).
// A keyframe observes each visible site (in the image, facing the camera, not occluded) with
// probability `detect` (with detect_spread > 0 each site its own: detect times a log-normal factor
// of mean 1 and log-sd detect_spread, at most 1; features differ in strength, so some are found
// by most keyframes that see them and many by few). The first observation of a site creates its map
// point: the site moved by stereo depth noise along the viewing ray, sigma_z = z^2 sigma_d / (f b),
// and `lateral_noise` across it; later keyframes observe that same position under the same id (as
// ORB-SLAM map points). A fraction `outliers` of each keyframe's observations are wrong stereo
// matches: new map points at depth z * U(0.5, 1.6) on the viewing ray. With the defaults they are
// isolated and seen by that keyframe only (the paper-like regime); the realistic SLAM outliers are
// parameters:
//   outlier_cluster   a wrong match is a patch of that many neighbouring features sharing one
//                     disparity error (a small wrong surface, as on repetitive texture): the
//                     points around the site within cluster_radius across the ray, all at the
//                     same depth factor; patches come outlier_cluster times less often, so
//                     `outliers` stays the fraction of wrong points a keyframe creates
//   outlier_repeat    the patch is re-observed (same ids, same world positions) by up to that many
//                     following keyframes that have it in their image (ORB-SLAM failing to cull
//                     or fuse it), each with probability repeat_prob
//   outlier_depth_gain the outlier rate grows as (z / radius)^gain with depth z and the depth
//                     error |factor - 1| as well (far matches are worse)
//   random_patches    outlier_cluster and outlier_repeat become maxima: every patch draws its
//                     size uniformly from 1..outlier_cluster and its lifetime from
//                     0..outlier_repeat (patches then come (1 + outlier_cluster) / 2 times less
//                     often than single wrong matches)
// With all of them at their defaults the random sequence, and so every keyframe, is the same as
// without them. seen_once_fraction() of the keyframes says how many distinct map points one
// keyframe alone observes (6.6 % on ../shared/data/orbslam2_stereo_keyframes, `knnocc eval --ids`).
// Keyframe clouds are in the camera frame (x right, y down, z forward) with camera-to-world
// poses, like ../shared/data/orbslam2_stereo_keyframes. Deterministic for a seed with a given
// compiler and math library (own uniform and normal variates on std::mt19937_64, so no
// standard-library distribution differs; libm's log/cos may round differently elsewhere).
//
// Thread safety: a TreeScene is one generator (next() advances it); use one per thread.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../eval/reference.hpp"
#include "../io/cloud.hpp"
#include "../io/sequence.hpp"
#include "../io/trajectory.hpp"

namespace knnocc::sim {

struct TreeSceneParams {
  std::uint64_t seed = 1;
  std::size_t keyframes = 60;  ///< around one full circle
  double radius = 3.5;         ///< camera circle radius (m)
  double height = 1.3;         ///< camera height (m)
  double focal = 700.0;        ///< px (ZED 720p)
  int width = 1280, height_px = 720;
  double baseline = 0.12;        ///< stereo baseline (m)
  double disparity_noise = 0.5;  ///< sigma_d (px)
  double lateral_noise = 0.01;   ///< across the viewing ray (m)
  double detect = 0.3;           ///< probability that a visible site is observed by a keyframe
  double detect_spread = 0.0;    ///< log-sd of the sites' own detection probabilities (0: equal)
  double outliers = 0.08;        ///< fraction of wrong stereo matches per keyframe
  double foliage_density = 150;  ///< feature sites per m^2
  double pot_density = 100;
  double ground_density = 12;
  double ground_radius = 6.0;       ///< textured ground around the tree (m)
  std::size_t outlier_cluster = 1;  ///< points per wrong match (a patch sharing its error)
  double cluster_radius = 0.03;     ///< the patch's extent across the viewing ray (m)
  std::size_t outlier_repeat = 0;   ///< following keyframes that may re-observe a patch
  double repeat_prob = 1.0;         ///< probability of each re-observation
  double outlier_depth_gain = 0.0;  ///< rate and depth error grow as (z / radius)^gain
  bool random_patches = false;      ///< sizes and lifetimes drawn per patch up to the two above

  void validate() const {
    if (keyframes < 1 || keyframes > 100000)
      knnocc::detail::invalid_argument("keyframes must be in [1, 100000]");
    if (!(radius > 1.5 && radius < 100))
      knnocc::detail::invalid_argument("radius must be in (1.5, 100) m");
    if (!(detect > 0 && detect <= 1)) knnocc::detail::invalid_argument("detect must be in (0, 1]");
    if (!(detect_spread >= 0 && detect_spread <= 3))
      knnocc::detail::invalid_argument("detect_spread must be in [0, 3]");
    if (!(outliers >= 0 && outliers < 1))
      knnocc::detail::invalid_argument("outliers must be in [0, 1)");
    if (!(disparity_noise >= 0 && lateral_noise >= 0 && disparity_noise < 100 &&
          lateral_noise < 10))
      knnocc::detail::invalid_argument("noise must be >= 0 (disparity < 100 px, lateral < 10 m)");
    auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };  // NaN fails
    if (!in(height, -100, 100)) knnocc::detail::invalid_argument("height must be in [-100, 100] m");
    if (!in(focal, 1, 1e5) || !in(baseline, 1e-3, 10) || width < 16 || height_px < 16 ||
        width > 100000 || height_px > 100000)
      knnocc::detail::invalid_argument(
          "camera: focal in [1, 1e5] px, baseline in [1 mm, 10 m], image sides in [16, 1e5] px");
    if (!in(foliage_density, 0, 1e4) || !in(pot_density, 0, 1e4) || !in(ground_density, 0, 1e4))
      knnocc::detail::invalid_argument("densities must be in [0, 1e4] sites per m^2");
    if (!in(ground_radius, 0, 100))
      knnocc::detail::invalid_argument("ground_radius must be in [0, 100] m");
    if (outlier_cluster < 1 || outlier_cluster > 100)
      knnocc::detail::invalid_argument("outlier_cluster must be in [1, 100]");
    if (!in(cluster_radius, 0, 1))
      knnocc::detail::invalid_argument("cluster_radius must be in [0, 1] m");
    if (outlier_repeat > 1000)
      knnocc::detail::invalid_argument("outlier_repeat must be in [0, 1000]");
    if (!in(repeat_prob, 0, 1)) knnocc::detail::invalid_argument("repeat_prob must be in [0, 1]");
    if (!in(outlier_depth_gain, 0, 10))
      knnocc::detail::invalid_argument("outlier_depth_gain must be in [0, 10]");
  }
};

struct SimKeyframe {
  io::Pose pose;             ///< camera to world (stamp = keyframe index)
  io::Cloud cloud;           ///< camera frame, one map-point id per point
  std::size_t outliers = 0;  ///< wrong matches among the points
  std::size_t patches = 0;   ///< wrong patches this keyframe created (not re-observed ones)
};

class TreeScene {
 public:
  explicit TreeScene(TreeSceneParams p = {}) : p_(p), rng_(p.seed) {
    p_.validate();
    ref_.has_ground = true;
    ref_.ground_z = 0.0;
    ref_.ellipsoids.push_back({{0.0, 0.0, 1.6}, {0.9, 0.9, 0.7}});  // foliage
    // Pot with its grass; faces off the voxel grids of 0.1 and 0.05 m, as real objects are.
    ref_.cuboids.push_back({{-0.27, -0.27, 0.0}, {0.27, 0.27, 0.77}});
    make_sites();
  }

  const eval::Reference& reference() const { return ref_; }
  const TreeSceneParams& params() const { return p_; }

  /// One circle of params().keyframes keyframes, from where the camera is (the start, for a new
  /// scene).
  std::vector<SimKeyframe> keyframes() {
    std::vector<SimKeyframe> out;
    for (std::size_t i = 0; i < p_.keyframes; ++i) out.push_back(next());
    return out;
  }

  /// The next keyframe; the camera keeps circling (params().keyframes per circle), observing the
  /// same map points, so long runs stay in one bounded scene.
  SimKeyframe next() { return keyframe(count_++); }

 private:
  struct Site {
    Eigen::Vector3d p, n;  // position and outward normal
  };
  struct Patch {  // a wrong patch that later keyframes may observe again
    std::vector<Eigen::Vector3d> world;
    std::vector<std::uint64_t> ids;
    std::size_t left = 0;  // re-observations still possible
    bool fresh = true;     // made by the keyframe being built
  };

  double uniform() { return (rng_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double normal() {                                        // Box-Muller
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  static std::size_t rounded(double mean) { return static_cast<std::size_t>(std::llround(mean)); }
  static std::size_t rounded_down(double v) { return static_cast<std::size_t>(std::floor(v)); }

  void make_sites() {
    const eval::Ellipsoid& e = ref_.ellipsoids[0];
    const Eigen::Vector3d c(e.centre.x, e.centre.y, e.centre.z),
        a(e.semi_axes.x, e.semi_axes.y, e.semi_axes.z);
    // Foliage: uniform directions mapped onto the ellipsoid, kept in proportion to the local
    // area element (rejection), then up to 5 cm inwards.
    const double area = 4 * M_PI *
                        std::pow((std::pow(a.x() * a.y(), 1.6) + std::pow(a.x() * a.z(), 1.6) +
                                  std::pow(a.y() * a.z(), 1.6)) /
                                     3,
                                 1 / 1.6);
    const std::size_t foliage = rounded(area * p_.foliage_density);
    while (sites_.size() < foliage) {
      Eigen::Vector3d u(normal(), normal(), normal());
      u.normalize();
      const Eigen::Vector3d n = Eigen::Vector3d(u.x() / a.x(), u.y() / a.y(), u.z() / a.z());
      // area element of x = a*u is proportional to |n| * a.x a.y a.z; accept with |n| / max|n|
      if (uniform() * (1.0 / std::min({a.x(), a.y(), a.z()})) > n.norm()) continue;
      const Eigen::Vector3d p = c + a.cwiseProduct(u);
      const Eigen::Vector3d normal_out = n.normalized();
      sites_.push_back({p - normal_out * (0.05 * uniform()), normal_out});
    }
    // Pot: its four sides and its top (the grass).
    const eval::Cuboid& b = ref_.cuboids[0];
    const Eigen::Vector3d lo(b.lo.x, b.lo.y, b.lo.z), hi(b.hi.x, b.hi.y, b.hi.z);
    const Eigen::Vector3d size = hi - lo;
    struct Face {
      int axis;
      bool high;
    };
    for (const Face f :
         {Face{0, false}, Face{0, true}, Face{1, false}, Face{1, true}, Face{2, true}}) {
      const int u = (f.axis + 1) % 3, v = (f.axis + 2) % 3;
      const std::size_t n = rounded(size[u] * size[v] * p_.pot_density);
      for (std::size_t i = 0; i < n; ++i) {
        Eigen::Vector3d p;
        p[f.axis] = f.high ? hi[f.axis] : lo[f.axis];
        p[u] = lo[u] + size[u] * uniform();
        p[v] = lo[v] + size[v] * uniform();
        Eigen::Vector3d nrm = Eigen::Vector3d::Zero();
        nrm[f.axis] = f.high ? 1 : -1;
        sites_.push_back({p, nrm});
      }
    }
    // Ground: a disc around the tree, outside the pot.
    const std::size_t ground =
        rounded(M_PI * p_.ground_radius * p_.ground_radius * p_.ground_density);
    for (std::size_t i = 0; i < ground; ++i) {
      const double r = p_.ground_radius * std::sqrt(uniform()), phi = 2 * M_PI * uniform();
      const Eigen::Vector3d p(r * std::cos(phi), r * std::sin(phi), 0.0);
      if (ref_.contains({p.x(), p.y(), 0.001})) continue;
      sites_.push_back({p, Eigen::Vector3d::UnitZ()});
    }
    map_points_.assign(sites_.size(), Eigen::Vector3d::Constant(std::nan("")));
    // Each site's detection probability (drawn only with a spread: the random sequence of the
    // default scene stays as it was).
    detect_.assign(sites_.size(), p_.detect);
    if (p_.detect_spread > 0)
      for (double& d : detect_) {
        const double s = p_.detect_spread;
        d = std::min(1.0, p_.detect * std::exp(s * normal() - 0.5 * s * s));
      }
  }

  // Does the segment from o to just before p cross a solid?
  bool occluded(const Eigen::Vector3d& o, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - o;
    const double stop = 1.0 - 0.08 / d.norm();          // sites lie up to 5 cm inside the foliage
    for (const eval::Ellipsoid& e : ref_.ellipsoids) {  // |(o + t d - c) / a|^2 = 1
      const Eigen::Vector3d a(e.semi_axes.x, e.semi_axes.y, e.semi_axes.z);
      const Eigen::Vector3d oc =
          (o - Eigen::Vector3d(e.centre.x, e.centre.y, e.centre.z)).cwiseQuotient(a);
      const Eigen::Vector3d dd = d.cwiseQuotient(a);
      const double A = dd.squaredNorm(), B = 2 * oc.dot(dd), C = oc.squaredNorm() - 1;
      const double disc = B * B - 4 * A * C;
      if (disc < 0) continue;
      const double t0 = (-B - std::sqrt(disc)) / (2 * A);
      if (t0 > 0 && t0 < stop) return true;
    }
    for (const eval::Cuboid& b : ref_.cuboids) {  // slabs
      double t0 = 0, t1 = stop;
      const double lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
      for (int i = 0; i < 3 && t0 <= t1; ++i) {
        if (d[i] == 0) {
          if (o[i] < lo[i] || o[i] > hi[i]) t1 = -1;
          continue;
        }
        double ta = (lo[i] - o[i]) / d[i], tb = (hi[i] - o[i]) / d[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 < t1 - 1e-9) return true;
    }
    return false;
  }

  SimKeyframe keyframe(std::size_t i) {
    SimKeyframe kf;
    const double angle = 2 * M_PI * (static_cast<double>(i) + 0.3 * (uniform() - 0.5)) /
                         static_cast<double>(p_.keyframes);
    const double r = p_.radius + 0.1 * normal(), h = p_.height + 0.05 * normal();
    const Eigen::Vector3d o(r * std::cos(angle), r * std::sin(angle), h);
    const Eigen::Vector3d target(0.0, 0.0, 1.0 + 0.1 * normal());
    const Eigen::Vector3d fwd = (target - o).normalized();
    const Eigen::Vector3d right = fwd.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = fwd.cross(right);
    Eigen::Matrix3d R;
    R.col(0) = right;
    R.col(1) = down;
    R.col(2) = fwd;
    kf.pose.stamp = static_cast<double>(i);
    kf.pose.t = o;
    kf.pose.q = Eigen::Quaterniond(R);
    const double cx = p_.width / 2.0, cy = p_.height_px / 2.0;
    for (std::size_t s = 0; s < sites_.size(); ++s) {
      const Site& site = sites_[s];
      const Eigen::Vector3d pc = R.transpose() * (site.p - o);
      if (pc.z() < 0.3) continue;
      const double u = p_.focal * pc.x() / pc.z() + cx, v = p_.focal * pc.y() / pc.z() + cy;
      if (u < 0 || u >= p_.width || v < 0 || v >= p_.height_px) continue;
      if (site.n.dot(o - site.p) <= 0) continue;  // seen from behind
      if (uniform() >= detect_[s]) continue;
      if (occluded(o, site.p)) continue;
      Eigen::Vector3d& mp = map_points_[s];
      if (std::isnan(mp.x())) {  // first observation: triangulate once
        const double z = pc.z();
        const double sigma_z = z * z * p_.disparity_noise / (p_.focal * p_.baseline);
        const Eigen::Vector3d ray = pc / z;
        Eigen::Vector3d cam = ray * (z + sigma_z * normal());
        cam += Eigen::Vector3d(normal(), normal(), 0.0) * p_.lateral_noise;
        mp = R * cam + o;
      }
      const double depth_scale =
          p_.outlier_depth_gain > 0 ? std::pow(pc.z() / p_.radius, p_.outlier_depth_gain) : 1.0;
      // a wrong stereo match (a patch of outlier_cluster points) instead of this site
      const double mean_size = p_.random_patches ? (1.0 + double(p_.outlier_cluster)) / 2
                                                 : static_cast<double>(p_.outlier_cluster);
      if (uniform() < p_.outliers * depth_scale / mean_size) {
        const double e = 1.1 * uniform();  // factor 0.5 + e, its error scaled by depth_scale
        const double factor =
            depth_scale == 1.0 ? 0.5 + e : std::max(0.2, 1.0 + (e - 0.5) * depth_scale);
        add_wrong_patch(kf, pc, factor, R, o);
        continue;
      }
      kf.cloud.points.push_back(to_f(R.transpose() * (mp - o)));
      kf.cloud.ids.push_back(s);
    }
    reobserve_patches(kf, R, o, cx, cy);
    return kf;
  }

  // A wrong match at depth factor `factor` on the ray to pc (camera frame), with the rest of its
  // patch: the same factor for points around pc across the ray.
  void add_wrong_patch(SimKeyframe& kf, const Eigen::Vector3d& pc, double factor,
                       const Eigen::Matrix3d& R, const Eigen::Vector3d& o) {
    Patch patch;
    std::size_t size = p_.outlier_cluster, lifetime = p_.outlier_repeat;
    if (p_.random_patches) {
      size = 1 + std::min(p_.outlier_cluster - 1, rounded_down(uniform() * double(size)));
      lifetime = std::min(lifetime, rounded_down(uniform() * double(lifetime + 1)));
    }
    ++kf.patches;
    for (std::size_t m = 0; m < size; ++m) {
      Eigen::Vector3d q = pc;
      if (m > 0) q += Eigen::Vector3d(normal(), normal(), 0.0) * (p_.cluster_radius / 2);
      const Eigen::Vector3d wrong = q * factor;
      const std::uint64_t id = kOutlierIdBase + next_outlier_++;
      kf.cloud.points.push_back(to_f(wrong));
      kf.cloud.ids.push_back(id);
      ++kf.outliers;
      if (p_.outlier_repeat > 0) {
        patch.world.push_back(R * wrong + o);
        patch.ids.push_back(id);
      }
    }
    if (lifetime > 0) {
      patch.left = lifetime;
      patches_.push_back(std::move(patch));
    }
  }

  // Earlier keyframes' wrong patches that this keyframe observes again (same ids and positions):
  // the points in its image, in front of it, each patch with probability repeat_prob.
  void reobserve_patches(SimKeyframe& kf, const Eigen::Matrix3d& R, const Eigen::Vector3d& o,
                         double cx, double cy) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < patches_.size(); ++i) {
      Patch& patch = patches_[i];
      if (patch.fresh) {  // made by this keyframe
        patch.fresh = false;
      } else {
        --patch.left;
        if (uniform() < p_.repeat_prob)
          for (std::size_t m = 0; m < patch.ids.size(); ++m) {
            const Eigen::Vector3d pc = R.transpose() * (patch.world[m] - o);
            if (pc.z() < 0.3) continue;
            const double u = p_.focal * pc.x() / pc.z() + cx, v = p_.focal * pc.y() / pc.z() + cy;
            if (u < 0 || u >= p_.width || v < 0 || v >= p_.height_px) continue;
            kf.cloud.points.push_back(to_f(pc));
            kf.cloud.ids.push_back(patch.ids[m]);
            ++kf.outliers;
          }
      }
      if (patch.left > 0) patches_[kept++] = std::move(patch);
    }
    patches_.resize(kept);
  }

  static Point3f to_f(const Eigen::Vector3d& v) {
    return Point3f{static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
  }

 public:
  /// Ids of wrong matches start here (site ids are below).
  static constexpr std::uint64_t kOutlierIdBase = 1000000000;

 private:
  TreeSceneParams p_;
  std::mt19937_64 rng_;
  eval::Reference ref_;
  std::vector<Site> sites_;
  std::vector<Eigen::Vector3d> map_points_;  // NaN until first observed
  std::vector<double> detect_;               // per site: its detection probability
  std::vector<Patch> patches_;               // wrong patches still re-observable
  std::uint64_t next_outlier_ = 0;
  std::size_t count_ = 0;  // keyframes made so far
};

/// Feeds keyframes (camera-frame clouds with poses) to a Mapper the way `knnocc map` does with a
/// sequence folder: points farther than `crop` from the camera dropped (<= 0: none), the rest
/// moved to the world frame, ids passed on. Returns the microseconds of each insert_keyframe.
template <class MapperT>
std::vector<double> map_keyframes(MapperT& mapper, const std::vector<SimKeyframe>& keyframes,
                                  double crop) {
  std::vector<double> us;
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  for (const SimKeyframe& kf : keyframes) {
    io::keyframe_to_world(kf.pose, kf.cloud, crop, world, ids);
    const auto a = std::chrono::steady_clock::now();
    mapper.insert_keyframe(kf.pose.t, world, ids);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count());
  }
  return us;
}

/// The fraction of the distinct map points (ids) within `crop` of their camera (<= 0: all) that
/// one keyframe alone observes.
inline double seen_once_fraction(const std::vector<SimKeyframe>& keyframes, double crop) {
  std::vector<std::uint64_t> ids;
  for (const SimKeyframe& kf : keyframes) {
    const std::size_t start = ids.size();
    for (std::size_t j = 0; j < kf.cloud.points.size(); ++j) {
      const Point3f& p = kf.cloud.points[j];
      if (crop <= 0 || std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= crop)
        ids.push_back(kf.cloud.ids[j]);
    }
    std::sort(ids.begin() + static_cast<std::ptrdiff_t>(start), ids.end());  // once per keyframe
    ids.erase(std::unique(ids.begin() + static_cast<std::ptrdiff_t>(start), ids.end()), ids.end());
  }
  std::sort(ids.begin(), ids.end());
  std::size_t distinct = 0, once = 0;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t j = i;
    while (j < ids.size() && ids[j] == ids[i]) ++j;
    ++distinct;
    once += j - i == 1;
    i = j;
  }
  return distinct ? double(once) / double(distinct) : 0.0;
}

}  // namespace knnocc::sim
