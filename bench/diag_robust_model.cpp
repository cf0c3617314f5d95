// diag_robust_model: what the robust model (sensor/robust_model.hpp) believes and why. For the
// simulator's regimes (seeds 1..N, optionally with other wrong patches) it prints the mixture's
// rates at the end of each seed and, for real points and wrong matches apart, how many the model
// believes and their counts (detections d, see-throughs c, independent support u); then the
// counts of the map points it still believes in irrelevant voxels. For the real sets with ids
// (../shared/data) it prints the rates and the believed fraction by number of detections.
//
//   build/bin/diag_robust_model [--seeds N] [--first-seed S] [--data DIR]
//                               [--repeat N] [--cluster N] [--repeat-prob P]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "regime_changes.hpp"

using namespace knnocc;

namespace {

struct Quartiles {
  std::vector<double> v;
  void add(double x) { v.push_back(x); }
  std::string text() {
    if (v.empty()) return "-";
    std::sort(v.begin(), v.end());
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g/%g/%g", v[v.size() / 4], v[v.size() / 2],
                  v[3 * v.size() / 4]);
    return buf;
  }
};

// Believed points of one kind and their counts.
struct Kind {
  std::size_t points = 0, believed = 0;
  Quartiles d, c, u;
  void add(const RobustModel& m, const MapPointLedger::Point& p) {
    const PointCounts k = m.counts(p);
    ++points;
    believed += p.believed;
    d.add(k.d);
    c.add(k.c);
    u.add(k.u);
  }
  void print(const char* name) {
    std::printf("    %-22s %6zu points, %5.1f %% believed; d %s, c %s, u %s (quartiles)\n", name,
                points, points ? 100.0 * double(believed) / double(points) : 0.0, d.text().c_str(),
                c.text().c_str(), u.text().c_str());
  }
};

void print_rates(const RobustModel& m) {
  const RealPointRates& r = m.rates();
  std::printf(
      "    rates: prior %.3f, see-through %.4f / %.4f, support %.1f / %.1f (real / wrong)%s\n",
      r.prior, r.e_real, r.e_wrong, r.u_real, r.u_wrong,
      m.wrong_class_found() ? "" : "; no wrong class found: every point believed");
}

void simulated(const sim::Regime& regime, int first, int seeds, int repeat, int cluster,
               double repeat_prob) {
  std::printf("\nregime %s\n", regime.name.c_str());
  Kind real, wrong, irrelevant;
  for (int s = first; s < first + seeds; ++s) {
    sim::TreeScene scene(bench::changed_params(regime, s, {repeat, cluster, repeat_prob}));
    Mapper<RobustModel> mapper(0.1);
    sim::map_keyframes(mapper, scene.keyframes(), 4.0);
    const RobustModel& m = mapper.model();
    std::printf("  seed %d\n", s);
    print_rates(m);
    const auto& ref = scene.reference();
    const auto& g = mapper.map().grid();
    m.map_points().for_each([&](std::uint64_t id, const MapPointLedger::Point& pt) {
      const bool is_wrong = id >= sim::TreeScene::kOutlierIdBase;
      (is_wrong ? wrong : real).add(m, pt);
      if (!pt.has_key || !pt.believed) return;
      const OcKey k = OcKey::unpack(pt.key);
      const Point3d c{g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2])};
      const auto v = mapper.map().logodds(k);
      if (v && mapper.map().is_occupied(*v) && c.z >= 0.3 && ref.distance(c) > 0.3)
        irrelevant.add(m, pt);
    });
  }
  std::printf("  all seeds\n");
  real.print("real points");
  wrong.print("wrong matches");
  irrelevant.print("believed, irrelevant");
}

void real_set(const std::string& dir, double res) {
  if (!std::filesystem::is_directory(dir)) {
    std::printf("\n(no %s: skipped)\n", dir.c_str());
    return;
  }
  const io::Sequence seq = io::Sequence::open(dir);
  Mapper<RobustModel> mapper(res);
  std::vector<Point3d> w;
  std::vector<std::uint64_t> ids;
  std::vector<PointEvidence> ev;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), 4.0, w, ids, &ev);
    mapper.insert_keyframe(seq.pose(i).t, w, ids, ev);
  }
  const RobustModel& m = mapper.model();
  std::printf("\n%s (%zu keyframes, %g m, 4 m crop)\n", dir.c_str(), seq.size(), res);
  print_rates(m);
  std::map<std::uint32_t, Kind> by_views;
  m.map_points().for_each([&](std::uint64_t, const MapPointLedger::Point& p) {
    by_views[std::min(p.views, 10u)].add(m, p);
  });
  for (auto& [views, kind] : by_views)
    kind.print((std::to_string(views) + (views == 10 ? "+" : "") + " detections").c_str());
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5, first = 1, repeat = -1, cluster = -1;
  double repeat_prob = -1;
  std::string data = "../shared/data";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool more = i + 1 < argc;
    if (a == "--seeds" && more)
      seeds = std::max(1, std::atoi(argv[++i]));
    else if (a == "--first-seed" && more)
      first = std::atoi(argv[++i]);
    else if (a == "--data" && more)
      data = argv[++i];
    else if (a == "--repeat" && more)
      repeat = std::atoi(argv[++i]);
    else if (a == "--cluster" && more)
      cluster = std::atoi(argv[++i]);
    else if (a == "--repeat-prob" && more)
      repeat_prob = std::atof(argv[++i]);
  }
  std::printf("diag_robust_model: seeds %d..%d\n", first, first + seeds - 1);
  for (const sim::Regime& r : sim::named_regimes())
    if (r.name == "repeated" || r.name == "realistic")
      simulated(r, first, seeds, repeat, cluster, repeat_prob);
  real_set(data + "/orbslam2_stereo_keyframes", 0.1);
  real_set(data + "/icl_living_room_traj2n", 0.05);
  return 0;
}
