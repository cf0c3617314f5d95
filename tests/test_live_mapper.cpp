// LiveMapper: after every operation of long random sequences (add, re-pose a few recent
// keyframes, re-pose scattered ones, re-pose all as a loop closure, re-pose to the same pose,
// remove), the map (every voxel's log-odds bit for bit, and which voxels are known) and the k-NN
// tracker (each map point's position and s_p, N, mu, sigma, bit for bit) equal a Mapper built
// from scratch over the current keyframes in insertion order with their current poses. Both
// models, with and without max range, with and without map-point ids; the sequences reach the
// clamping bounds (checked) and the OctoMap model's regional replay is exercised (checked).

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <type_traits>
#include <utility>
#include <vector>

#include <knnocc/core/memory_limit.hpp>
#include <knnocc/live/live_mapper.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}
std::uint64_t bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// A corridor of pillars along x: a sensor moving along it sees a few metres, so re-posing recent
// keyframes changes a region that old keyframes do not reach.
struct Scene {
  std::vector<Point3d> surface;
  explicit Scene(test::Rng& rng, double length) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (double x = 0.0; x < length; x += 1.1) {
      const double cy = (u(rng) < 0.5 ? -1.0 : 1.0) * (0.8 + 0.6 * u(rng));
      for (int i = 0; i < 40; ++i) {  // a pillar of radius 0.25
        const double a = 2 * M_PI * u(rng), z = 1.5 * u(rng);
        surface.push_back({x + 0.25 * std::cos(a), cy + 0.25 * std::sin(a), z});
      }
    }
    for (int i = 0; i < static_cast<int>(length * 25); ++i)  // the floor
      surface.push_back({length * u(rng), 4.0 * u(rng) - 2.0, 0.0});
  }
};

struct Frame {
  RigidPose pose;
  std::vector<Point3f> points;
  std::vector<std::uint64_t> ids;
};

// Keyframe f: the sensor at x = 0.35 f with a small yaw, seeing the surface within 3 m (a third
// of it, at random) with noise; points in the sensor frame.
Frame make_frame(test::Rng& rng, const Scene& scene, int f, bool with_ids) {
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Frame fr;
  fr.pose = RigidPose::yaw(0.2 * (u(rng) - 0.5), 0.35 * f, 0.1 * (u(rng) - 0.5), 0.8);
  for (std::size_t i = 0; i < scene.surface.size(); ++i) {
    const Point3d& s = scene.surface[i];
    const double dx = s.x - fr.pose.t[0], dy = s.y - fr.pose.t[1], dz = s.z - fr.pose.t[2];
    if (dx * dx + dy * dy + dz * dz > 9.0 || u(rng) < 0.6) continue;
    const double wx = dx + noise(rng), wy = dy + noise(rng), wz = dz + noise(rng);
    const auto& r = fr.pose.r;  // R^T (w - t)
    fr.points.push_back({static_cast<float>(r[0] * wx + r[3] * wy + r[6] * wz),
                         static_cast<float>(r[1] * wx + r[4] * wy + r[7] * wz),
                         static_cast<float>(r[2] * wx + r[5] * wy + r[8] * wz)});
    if (with_ids) fr.ids.push_back(i);
  }
  return fr;
}

RigidPose perturbed(test::Rng& rng, const RigidPose& p, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double yaw = std::atan2(p.r[3], p.r[0]) + 0.05 * scale * u(rng);
  return RigidPose::yaw(yaw, p.t[0] + 0.15 * scale * u(rng), p.t[1] + 0.15 * scale * u(rng),
                        p.t[2] + 0.05 * scale * u(rng));
}

// The oracle: Mapper from scratch over the live mapper's current keyframes.
template <class Model, class Live>
void check_against_scratch(const Live& live, const Model& model, const MapperOptions& options,
                           double res) {
  Mapper<Model> scratch(res, model, options);
  std::vector<Point3d> world;
  for (const auto& kf : live.keyframes().frames()) {
    world.clear();
    for (const Point3f& p : kf.points)
      world.push_back(pose_traits<RigidPose>::to_world(kf.pose, p));
    const Point3d o = pose_traits<RigidPose>::origin(kf.pose);
    if constexpr (Mapper<Model>::uses_map_cloud)
      scratch.insert_keyframe(o, world, kf.ids);
    else
      scratch.insert_keyframe(o, world);
  }
  std::map<std::uint64_t, std::uint32_t> want, got;
  scratch.map().for_each_voxel([&](const auto& k, float v) { want[k.pack()] = bits(v); });
  live.map().for_each_voxel([&](const auto& k, float v) { got[k.pack()] = bits(v); });
  REQUIRE(got.size() == want.size());
  REQUIRE(live.map().num_voxels() == scratch.map().num_voxels());
  CHECK(got == want);
  if constexpr (Mapper<Model>::uses_map_cloud) {
    const auto& a = live.tracker();
    const auto& b = scratch.tracker();
    REQUIRE(a.size() == b.size());
    CHECK(a.N() == b.N());
    CHECK(bits(a.mu()) == bits(b.mu()));
    CHECK(bits(a.sigma()) == bits(b.sigma()));
    using Rec = std::array<std::uint64_t, 4>;
    std::map<std::uint64_t, Rec> pa, pb;
    a.for_each_point([&](std::uint64_t id, const Point3d& p, double s) {
      pa[id] = Rec{bits(p.x), bits(p.y), bits(p.z), bits(s)};
    });
    b.for_each_point([&](std::uint64_t id, const Point3d& p, double s) {
      pb[id] = Rec{bits(p.x), bits(p.y), bits(p.z), bits(s)};
    });
    CHECK(pa == pb);
  }
}

struct Counts {
  std::size_t regional = 0, rebuilt = 0, at_max = 0, at_min = 0;
};

template <class Model>
Counts random_operations(std::uint64_t seed, const Model& model, double max_range, bool with_ids,
                         int operations) {
  test::Rng rng(seed);
  const double res = 0.1;
  const Scene scene(rng, 40.0);
  MapperOptions options;
  options.max_range = max_range;
  LiveMapper<Model> live(res, model, options);
  std::vector<std::uint64_t> alive;             // ids in insertion order
  std::map<std::uint64_t, RigidPose> original;  // re-poses scatter around these
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Counts counts;
  int next_frame = 0;
  std::uint64_t next_id = 100;
  for (int op = 0; op < operations; ++op) {
    const double r = u(rng);
    std::string what;
    if (alive.size() < 4 || r < 0.50) {
      what = "add";
      const Frame fr = make_frame(rng, scene, next_frame++ % 110, with_ids);
      live.add(next_id, fr.pose, fr.points, fr.ids);
      original[next_id] = fr.pose;
      alive.push_back(next_id++);
    } else if (r < 0.70) {  // local bundle adjustment: the last 1..6 keyframes
      what = "repose recent";
      std::vector<std::pair<std::uint64_t, RigidPose>> poses;
      const std::size_t n = 1 + rng() % std::min<std::size_t>(6, alive.size());
      for (std::size_t j = alive.size() - n; j < alive.size(); ++j)
        poses.emplace_back(alive[j], perturbed(rng, original[alive[j]], 1.0));
      live.repose(poses);
    } else if (r < 0.80) {  // scattered keyframes, one of them to its own pose (no change)
      what = "repose scattered";
      std::vector<std::pair<std::uint64_t, RigidPose>> poses;
      for (int j = 0; j < 3; ++j) {
        const std::uint64_t id = alive[rng() % alive.size()];
        poses.emplace_back(id, perturbed(rng, original[id], 0.5));
      }
      const std::uint64_t same = alive[rng() % alive.size()];
      poses.emplace_back(same, live.pose(same));
      live.repose(poses);
    } else if (r < 0.84) {  // loop closure: every keyframe
      what = "repose all";
      std::vector<std::pair<std::uint64_t, RigidPose>> poses;
      for (const std::uint64_t id : alive)
        poses.emplace_back(id, perturbed(rng, original[id], 0.3));
      live.repose(poses);
    } else {  // keyframe culling
      what = "remove";
      std::vector<std::uint64_t> gone;
      const std::size_t n = 1 + rng() % 2;
      for (std::size_t j = 0; j < n; ++j) gone.push_back(alive[rng() % alive.size()]);
      live.remove(gone);
      std::vector<std::uint64_t> rest;
      for (const std::uint64_t id : alive)
        if (live.contains(id)) rest.push_back(id);
      alive = rest;
    }
    if (!live.last_update().rebuilt && live.last_update().replayed > 0 && what != "add")
      ++counts.regional;
    counts.rebuilt += live.last_update().rebuilt;
    CAPTURE(op);
    CAPTURE(what);
    REQUIRE(live.size() == alive.size());
    check_against_scratch(live, model, options, res);
    live.map().for_each_voxel([&](const auto&, float v) {
      counts.at_max += v == live.map().params().clamp_max;
      counts.at_min += v == live.map().params().clamp_min;
    });
  }
  return counts;
}

}  // namespace

TEST_CASE("live_mapper.octomap_model_equals_rebuild_after_random_operations") {
  for (const double max_range : {-1.0, 2.0}) {
    CAPTURE(max_range);
    const Counts c = random_operations(11 + (max_range > 0), OctoMapModel{}, max_range, false, 160);
    CHECK(c.regional > 20);  // most corrections replayed a region, not the map
    CHECK(c.at_max > 0);     // the clamping bounds were reached
    CHECK(c.at_min > 0);
  }
}

TEST_CASE("live_mapper.knn_model_equals_rebuild_after_random_operations") {
  for (const bool with_ids : {false, true})
    for (const double max_range : {-1.0, 2.0}) {
      CAPTURE(with_ids);
      CAPTURE(max_range);
      const Counts c = random_operations(31 + 2 * with_ids + (max_range > 0), KnnModel{}, max_range,
                                         with_ids, 70);
      CHECK(c.rebuilt > 0);
      CHECK(c.at_max > 0);
      CHECK(c.at_min > 0);
    }
}

TEST_CASE("live_mapper.movable") {
  for (const bool with_ids : {false, true}) {
    CAPTURE(with_ids);
    static_assert(std::is_move_constructible_v<LiveMapper<KnnModel>>);
    static_assert(std::is_move_assignable_v<LiveMapper<OctoMapModel>>);
    test::Rng rng(17);
    const Scene scene(rng, 10.0);
    LiveMapper<KnnModel> live(0.1);
    for (int f = 0; f < 6; ++f) {
      const Frame fr = make_frame(rng, scene, f, with_ids);
      live.add(static_cast<std::uint64_t>(f), fr.pose, fr.points, fr.ids);
    }
    LiveMapper<KnnModel> moved(std::move(live));
    for (int f = 6; f < 10; ++f) {
      const Frame fr = make_frame(rng, scene, f, with_ids);
      moved.add(static_cast<std::uint64_t>(f), fr.pose, fr.points, fr.ids);
    }
    moved.repose({{2, make_frame(rng, scene, 3, with_ids).pose}});
    moved.remove({4});
    CHECK(moved.size() == 9);
    check_against_scratch(moved, KnnModel{}, MapperOptions{}, 0.1);
    LiveMapper<OctoMapModel> octo(0.1), other(0.2);
    const Frame fr = make_frame(rng, scene, 1, false);
    octo.add(1, fr.pose, fr.points);
    other = std::move(octo);
    other.add(2, make_frame(rng, scene, 2, false).pose, fr.points);
    other.repose({{1, make_frame(rng, scene, 5, false).pose}});
    check_against_scratch(other, OctoMapModel{}, MapperOptions{}, 0.1);
  }
}

TEST_CASE("live_mapper.bad_operations_change_nothing") {
  test::Rng rng(5);
  const Scene scene(rng, 10.0);
  LiveMapper<KnnModel> live(0.1);
  const Frame a = make_frame(rng, scene, 1, true), b = make_frame(rng, scene, 2, false);
  live.add(1, a.pose, a.points, a.ids);
  const std::size_t voxels = live.map().num_voxels();
  CHECK_THROWS_AS(live.add(1, a.pose, a.points, a.ids), std::invalid_argument);  // id again
  CHECK_THROWS_AS(live.add(2, b.pose, b.points, b.ids), std::invalid_argument);  // ids mixed
  Frame twice = a;
  twice.ids.back() = twice.ids.front();  // one map point observed twice by one keyframe
  CHECK_THROWS_WITH_AS(live.add(3, twice.pose, twice.points, twice.ids),
                       doctest::Contains("appears twice in one keyframe"), std::invalid_argument);
  CHECK_THROWS_AS(live.repose({{7, a.pose}}), std::invalid_argument);  // unknown id
  CHECK_THROWS_AS(live.remove({1, 7}), std::invalid_argument);         // unknown id
  RigidPose nan_pose = a.pose;
  nan_pose.t[0] = std::nan("");
  CHECK_THROWS_AS(live.repose({{1, nan_pose}}), std::invalid_argument);
  CHECK(live.size() == 1);
  CHECK(live.map().num_voxels() == voxels);
  // Once the keyframes with ids are gone, keyframes without ids are welcome.
  live.remove({1});
  CHECK(live.map().num_voxels() == 0);
  live.add(2, b.pose, b.points, b.ids);
  check_against_scratch(live, KnnModel{}, MapperOptions{}, 0.1);
}

TEST_CASE_TEMPLATE("live_mapper.memory_limit_holds_through_rebuilds_and_replays", Model,
                   OctoMapModel, KnnModel) {
  test::Rng rng(13);
  const Scene scene(rng, 12.0);
  std::vector<Frame> frames;
  for (int f = 0; f < 30; ++f) frames.push_back(make_frame(rng, scene, f, true));
  LiveMapper<Model> unbounded(0.1);
  for (int f = 0; f < 30; ++f) unbounded.add(f, frames[f].pose, frames[f].points, frames[f].ids);
  const std::size_t full = unbounded.map().memory_usage();

  // Room for the whole map: adds, a regional replay (OctoMap model) or a rebuild (k-NN) of a
  // re-pose and a loop closure all fit, and the map equals the from-scratch one.
  LiveMapper<Model> roomy(0.1);
  roomy.set_memory_limit(4 * full);  // checks before growth are conservative
  for (int f = 0; f < 30; ++f) roomy.add(f, frames[f].pose, frames[f].points, frames[f].ids);
  roomy.repose({{28, perturbed(rng, frames[28].pose, 1.0)}});
  check_against_scratch(roomy, Model{}, MapperOptions{}, 0.1);
  std::vector<std::pair<std::uint64_t, RigidPose>> all;
  for (int f = 0; f < 30; ++f) all.emplace_back(f, perturbed(rng, frames[f].pose, 0.5));
  roomy.repose(all);
  CHECK(roomy.last_update().rebuilt);
  CHECK(roomy.map().memory_limit() == 4 * full);  // the rebuilt map keeps the limit
  check_against_scratch(roomy, Model{}, MapperOptions{}, 0.1);

  // Half of it: adding the keyframes stops at the limit.
  LiveMapper<Model> tight(0.1);
  tight.set_memory_limit(full / 2);
  bool refused = false;
  for (int f = 0; f < 30 && !refused; ++f) {
    try {
      tight.add(f, frames[f].pose, frames[f].points, frames[f].ids);
    } catch (const MemoryLimitError&) {
      refused = true;
    }
    CHECK(tight.map().memory_usage() <= full / 2);
  }
  CHECK(refused);

  // A limit set on a full map binds the rebuild of a loop closure; raised, rebuild() recovers.
  unbounded.set_memory_limit(full / 2);
  CHECK_THROWS_AS(unbounded.repose(all), MemoryLimitError);
  unbounded.set_memory_limit(0);
  unbounded.rebuild();
  check_against_scratch(unbounded, Model{}, MapperOptions{}, 0.1);
}

TEST_CASE("live_mapper.recent_repose_replays_only_nearby_keyframes") {
  test::Rng rng(9);
  const Scene scene(rng, 40.0);
  LiveMapper<OctoMapModel> live(0.1);
  for (int f = 0; f < 100; ++f) {
    const Frame fr = make_frame(rng, scene, f, false);
    live.add(static_cast<std::uint64_t>(f), fr.pose, fr.points);
  }
  live.repose({{99, perturbed(rng, live.pose(99), 1.0)}});
  CHECK_FALSE(live.last_update().rebuilt);
  CHECK(live.last_update().replayed < 30);  // the sensor sees 3 m, keyframes are 0.35 m apart
  check_against_scratch(live, OctoMapModel{}, MapperOptions{}, 0.1);
  // An id named twice: the last pose wins; removing an id twice removes it once.
  const RigidPose last = perturbed(rng, live.pose(98), 1.0);
  live.repose({{98, perturbed(rng, live.pose(98), 1.0)}, {97, live.pose(97)}, {98, last}});
  CHECK(live.last_update().changed == 1);
  CHECK(live.pose(98) == last);
  check_against_scratch(live, OctoMapModel{}, MapperOptions{}, 0.1);
  live.remove({50, 50, 97});
  CHECK(live.last_update().changed == 2);
  CHECK(live.size() == 98);
  check_against_scratch(live, OctoMapModel{}, MapperOptions{}, 0.1);
}

TEST_CASE_TEMPLATE("live_mapper.point_counts_are_a_from_scratch_mappers", Model, OctoMapModel,
                   KnnModel) {
  // A correction moves keyframe 2 4 km away: at 0.1 m (+-3.3 km of keys) its points leave the
  // map, and the counts are those of a Mapper fed the keyframes at their new poses.
  test::Rng rng(11);
  const Scene scene(rng, 8.0);
  const MapperOptions options{2.5, false, 1, {}};
  LiveMapper<Model> live(0.1, Model{}, options);
  std::vector<Frame> frames;
  for (int f = 0; f < 4; ++f) {
    frames.push_back(make_frame(rng, scene, f, true));
    frames.back().points.push_back({std::nanf(""), 0.f, 0.f});  // one NaN point each
    frames.back().ids.push_back(900000 + f);
    live.add(f, frames.back().pose, frames.back().points, frames.back().ids);
  }
  const RigidPose far = RigidPose::yaw(0.1, 4000.0, 0.0, 0.8);
  live.repose({{2, far}});
  Mapper<Model> scratch(0.1, Model{}, options);
  ScanStats want;
  std::vector<Point3d> world;
  for (int f = 0; f < 4; ++f) {
    const RigidPose& pose = f == 2 ? far : frames[f].pose;
    world.clear();
    for (const Point3f& p : frames[f].points)
      world.push_back(pose_traits<RigidPose>::to_world(pose, p));
    const ScanStats s =
        scratch.insert_keyframe(pose_traits<RigidPose>::origin(pose), world, frames[f].ids).scan;
    want.points += s.points;
    want.nonfinite += s.nonfinite;
    want.out_of_range += s.out_of_range;
    want.beyond_max_range += s.beyond_max_range;
  }
  const ScanStats got = live.point_counts();
  CHECK(got.points == want.points);
  CHECK(got.nonfinite == 4);
  CHECK(got.nonfinite == want.nonfinite);
  CHECK(got.out_of_range == want.out_of_range);
  CHECK(got.out_of_range > 0);
  CHECK(got.beyond_max_range == want.beyond_max_range);
  CHECK(got.beyond_max_range > 0);
}
