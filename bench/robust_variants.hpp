// robust_variants: the robust model's ablations (docs/robust_model.md), measured by
// bench_robust_model --ablate. Each variant changes one of the rules RobustRules names
// (sensor/robust_model.hpp) or one parameter; none of them is a switch of the library's model.

#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <knnocc/eval/heldout.hpp>
#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

namespace knnocc::bench {

// The gap term on: keyframes between a point's first and latest detection that missed it.
struct WithGaps : RobustRules {
  static constexpr MixtureTerms terms{true};
};
// The mixture used even when its wrong class is not less supported than its real class.
struct WithoutSupportCheck : RobustRules {
  static constexpr bool support_check = false;
};
// Rays from the first or second detection of a believed point (the model: from the third).
struct RaysFromOne : RobustRules {
  static constexpr std::uint32_t ray_detections = 1;
};
struct RaysFromTwo : RobustRules {
  static constexpr std::uint32_t ray_detections = 2;
};
// See-throughs once per keyframe and voxel, whatever map point the rays end at (the model: each
// map point a ray ends at counts once per voxel).
struct SeeThroughPerKeyframe : RobustRules {
  static constexpr bool witness_once = false;
};
// Free rays also through voxels that hold another believed point (the model: not cast).
struct RaysThroughBelieved : RobustRules {
  static constexpr bool rays_through_believed = true;
};
// Both: the rules before witnesses and uncast rays.
struct PerKeyframeAndThrough : RobustRules {
  static constexpr bool witness_once = false;
  static constexpr bool rays_through_believed = true;
};
// Support negative binomial in the mixture (the model: geometric).
struct NbSupport : RobustRules {
  static constexpr MixtureTerms terms{false, true};
};
// The strength floor also for points a keyframe has seen through (the model: only for points
// never seen through).
struct FloorSeenThrough : RobustRules {
  static constexpr bool floor_when_seen_through = true;
};
// Without independent support (the mixture sees every point with none).
struct WithoutSupport : RobustRules {
  static constexpr bool support_check = false;  // nothing to check
  static PointCounts counts(const MapPointLedger::Point& p, const VoxelTally& t) {
    PointCounts k = RobustRules::counts(p, t);
    k.u = 0;
    return k;
  }
};
// Without see-throughs (the mixture sees every point never seen through).
struct WithoutSeeThrough : RobustRules {
  static PointCounts counts(const MapPointLedger::Point& p, const VoxelTally& t) {
    PointCounts k = RobustRules::counts(p, t);
    k.c = 0;
    return k;
  }
};

/// A variant: its name and how it maps simulated keyframes (the map's Table 1 metrics and the
/// median milliseconds per keyframe added to ms), a real sequence at a resolution and crop (the
/// map handed to use), and some of a real sequence's keyframes (the held-out evaluation's train).
struct RobustVariant {
  std::string name;
  std::function<eval::Metrics(const std::vector<sim::SimKeyframe>&, const eval::Reference&,
                              double&)>
      sim;
  std::function<double(const io::Sequence&, double res, double crop,
                       const std::function<void(const OccupancyMap<OcKey>&)>&)>
      real;
  std::function<OccupancyMap<OcKey>(const std::vector<eval::IdKeyframe>&,
                                    const std::vector<std::size_t>& train, double res)>
      train;
};

/// f(name, model) for the default model ("robust") and then each variant, in the ablation's order.
template <class F>
void for_each_robust_variant(F&& f) {
  f("robust", RobustModel{});
  for (const double m : {1.0, 3.0}) {
    RobustModelParams p;
    p.margin_scale = m;
    f(m == 1.0 ? "margin1" : "margin3", RobustModel(p));
  }
  f("+gaps", BasicRobustModel<WithGaps>{});
  f("-check", BasicRobustModel<WithoutSupportCheck>{});
  f("-support", BasicRobustModel<WithoutSupport>{});
  f("-seethru", BasicRobustModel<WithoutSeeThrough>{});
  f("rays1", BasicRobustModel<RaysFromOne>{});
  f("rays2", BasicRobustModel<RaysFromTwo>{});
  f("-witness", BasicRobustModel<SeeThroughPerKeyframe>{});
  f("+through", BasicRobustModel<RaysThroughBelieved>{});
  f("-both", BasicRobustModel<PerKeyframeAndThrough>{});
  f("nbsupport", BasicRobustModel<NbSupport>{});
  f("+floor", BasicRobustModel<FloorSeenThrough>{});
}

/// The variants' names (not the default's), comma-separated, for messages.
inline std::string robust_variant_names() {
  std::string names;
  for_each_robust_variant([&](const std::string& name, const auto&) {
    if (name != "robust") names += (names.empty() ? "" : ", ") + name;
  });
  return names;
}

/// The default model and, with ablate, its variants; map_sim, map_real and map_train are the
/// bench's own runners, templated on the model.
template <class MapSim, class MapReal, class MapTrain>
std::vector<RobustVariant> robust_variants(bool ablate, MapSim map_sim, MapReal map_real,
                                           MapTrain map_train) {
  std::vector<RobustVariant> v;
  auto add = [&](const std::string& name, const auto& model) {
    if (!ablate && name != "robust") return;
    v.push_back(RobustVariant{
        name,
        [=](const std::vector<sim::SimKeyframe>& kfs, const eval::Reference& ref, double& ms) {
          return map_sim(kfs, ref, model, ms);
        },
        [=](const io::Sequence& seq, double res, double crop,
            const std::function<void(const OccupancyMap<OcKey>&)>& use) {
          return map_real(seq, res, crop, model, use);
        },
        [=](const std::vector<eval::IdKeyframe>& kfs, const std::vector<std::size_t>& train,
            double res) { return map_train(kfs, train, res, model); }});
  };
  for_each_robust_variant(add);
  return v;
}

}  // namespace knnocc::bench
