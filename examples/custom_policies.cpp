// Mapper's parts are policies: this example writes its own sensor model and its own tracker, and
// passes a constructed library tracker, on the built-in simulated tree scene.
//
//   GatedModel          a rated sensor model (sensor/sensor_model.hpp): OctoMap's hit and miss
//                       values, but only endpoints whose mean k-NN distance s lies within
//                       mu + 2 sigma count; the others neither mark their voxel nor cast a ray
//   BruteForceTracker   a tracker (knn/tracker_concept.hpp) that recomputes every s from scratch
//                       after each change: O(n^2) per keyframe, fine for a few thousand points,
//                       and a check on KnnTracker (both follow the same definition of s)
//   KnnTracker<PaperAnnulus>  the library's tracker with the paper's Alg. 1 for affected points,
//                       constructed with its own radius step and search limit
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <vector>

#include <knnocc/core/log_odds.hpp>
#include <knnocc/knn/tracker.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

namespace {

struct GatedModel {
  static constexpr bool uses_map_cloud = true;    // rate() needs the map cloud's k-NN statistics
  using tracker_type = knnocc::KnnTracker<>;      // the default tracker...
  knnocc::TrackerParams tracker_params() const {  // ...made with these parameters
    knnocc::TrackerParams p;
    p.k = 8;
    return p;
  }
  float miss_logodds() const { return knnocc::logodds(0.4); }
  knnocc::EndpointRating rate(double s, const knnocc::RunningNormal& d) const {
    const bool reliable = d.count() > 0 && !std::isnan(s) && s <= d.mean() + 2.0 * d.sigma();
    return reliable ? knnocc::EndpointRating{knnocc::logodds(0.7), true}
                    : knnocc::EndpointRating{0.0f, false};
  }
};

// s by definition: the mean distance to the k nearest other points, ties broken by id.
class BruteForceTracker {
 public:
  explicit BruteForceTracker(std::size_t k = 8) : k_(k) {}

  knnocc::TrackerUpdate apply(const knnocc::ChangeSet& change) {
    knnocc::TrackerUpdate u;
    for (const std::uint64_t id : change.removed) u.removed += points_.erase(id);
    for (const knnocc::IdPoint& m : change.moved) points_[m.id] = m.p, ++u.moved;
    for (const knnocc::IdPoint& a : change.added) points_[a.id] = a.p, ++u.added;
    s_.clear();
    dist_ = knnocc::RunningNormal();
    std::vector<std::pair<double, std::uint64_t>> others;
    for (const auto& [id, p] : points_) {
      others.clear();
      for (const auto& [jd, q] : points_)
        if (jd != id) others.push_back({knnocc::dist2(p, q), jd});
      double s = std::numeric_limits<double>::quiet_NaN();
      if (others.size() >= k_) {
        std::partial_sort(others.begin(), others.begin() + static_cast<std::ptrdiff_t>(k_),
                          others.end());
        double sum = 0;
        for (std::size_t j = 0; j < k_; ++j) sum += std::sqrt(others[j].first);
        s = sum / static_cast<double>(k_);
        dist_.add(s);
      }
      s_[id] = s;
    }
    return u;
  }
  bool contains(std::uint64_t id) const { return s_.count(id) > 0; }
  double s(std::uint64_t id) const { return s_.at(id); }
  const knnocc::RunningNormal& distribution() const { return dist_; }

 private:
  std::size_t k_;
  std::map<std::uint64_t, knnocc::Point3d> points_;
  std::map<std::uint64_t, double> s_;
  knnocc::RunningNormal dist_;
};

template <class M>
void report(const char* name, const M& mapper) {
  const auto c = mapper.map().count_voxels();
  const auto& d = mapper.tracker().distribution();
  std::printf("%-28s occupied %5zu  free %6zu  map points %zu  mu %.6f  sigma %.6f\n", name,
              c.occupied, c.free, d.count(), d.mean(), d.sigma());
}

}  // namespace

int main() {
  knnocc::sim::TreeScene scene;  // seed 1, 60 keyframes around a potted tree
  const auto keyframes = scene.keyframes();

  knnocc::Mapper<GatedModel> gated(0.1);  // GatedModel's own tracker_type
  knnocc::sim::map_keyframes(gated, keyframes, /*crop=*/4.0);
  report("gated, KnnTracker", gated);

  knnocc::Mapper<GatedModel, knnocc::OcKey, BruteForceTracker> brute(0.1, GatedModel{},
                                                                     BruteForceTracker(8));
  knnocc::sim::map_keyframes(brute, keyframes, /*crop=*/4.0);
  report("gated, BruteForceTracker", brute);

  knnocc::TrackerParams params;
  params.k = 8;
  using PaperTracker = knnocc::KnnTracker<knnocc::PaperAnnulus>;
  knnocc::Mapper<knnocc::KnnModel, knnocc::OcKey, PaperTracker> paper(
      0.1, knnocc::KnnModel(), PaperTracker(params, knnocc::PaperAnnulus{0.05, 1.0}));
  knnocc::sim::map_keyframes(paper, keyframes, /*crop=*/4.0);
  report("k-NN model, paper's Alg. 1", paper);

  // Both trackers follow the same definition of s: their statistics agree (to rounding, since
  // one is updated incrementally and the other recomputed).
  const auto &a = gated.tracker().distribution(), &b = brute.tracker().distribution();
  const bool agree = a.count() == b.count() && std::fabs(a.mean() - b.mean()) < 1e-9 &&
                     std::fabs(a.sigma() - b.sigma()) < 1e-9;
  std::printf("trackers agree: %s\n", agree ? "yes" : "no");
  return agree ? 0 : 1;
}
