// diag_robust_model: what the robust model (sensor/robust_model.hpp) believes and why. For the
// simulator's regimes (seeds 1..N, optionally with other wrong patches) it prints the mixture's
// rates at the end of each seed and, for real points and wrong matches apart, how many the model
// believes and their counts (detections d, see-throughs c, independent support u); then the
// counts of the map points it still believes in irrelevant voxels. For the real sets with ids
// (../shared/data) it prints the rates and the believed fraction by number of detections; for the
// stereo set also what the held-out contradictions left at a 0.3 m margin are (eval/heldout.hpp:
// the seen-through voxels of the robust model's fold maps, whether OctoMap's maps have them too,
// the believed points they hold and the held-out rays through them).
//
//   build/bin/diag_robust_model [--seeds N] [--first-seed S] [--data DIR]
//                               [--repeat N] [--cluster N] [--repeat-prob P]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <knnocc/eval/heldout.hpp>
#include <knnocc/eval/id_keyframes.hpp>
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
    std::snprintf(buf, sizeof buf, "%.3g/%.3g/%.3g", v[v.size() / 4], v[v.size() / 2],
                  v[3 * v.size() / 4]);
    return buf;
  }
  // "quartiles, min-max"
  std::string with_range() {
    if (v.empty()) return "-";
    const std::string q = text();
    char buf[64];
    std::snprintf(buf, sizeof buf, ", %.3g-%.3g", v.front(), v.back());
    return q + buf;
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
  Kind real, wrong, irrelevant, ground;
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
      if (!is_wrong && std::fabs(pt.position.z) < 0.1 && ref.distance(pt.position) > 0.3)
        ground.add(m, pt);
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
  ground.print("real, on the ground");
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

// The held-out rays through the map's seen-through voxels (eval::for_each_seen_through, the walk
// score_heldout counts them with).
struct RaysThrough {
  std::size_t rays = 0, crossings = 0, believed_ends = 0, doubted_ends = 0;
  Quartiles length;       // per ray
  Quartiles past, aside;  // per crossing: voxel centre to the ray's point; ray to the nearest
                          // believed point in the voxel
};
void rays_through(const std::vector<eval::IdKeyframe>& kfs, const std::vector<std::size_t>& held,
                  const Mapper<RobustModel>& mapper, const eval::HeldoutOptions& opt,
                  RaysThrough& out) {
  const RobustModel& m = mapper.model();
  std::unordered_map<std::uint64_t, std::vector<Point3d>> believed;  // voxel -> its believed points
  m.map_points().for_each([&](std::uint64_t, const MapPointLedger::Point& p) {
    if (p.has_key && p.believed) believed[p.key].push_back(p.position);
  });
  const Grid<OcKey>& g = mapper.map().grid();
  std::size_t ray_kf = kfs.size(), ray_point = 0;  // the ray being walked
  auto cross = [&](std::size_t i, std::size_t j, const OcKey& k) {
    const Point3d& o = kfs[i].origin;
    const Point3d& e = kfs[i].points[j];
    const double dx = e.x - o.x, dy = e.y - o.y, dz = e.z - o.z;
    const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (i != ray_kf || j != ray_point) {  // a ray's crossings come one after another
      ray_kf = i, ray_point = j;
      ++out.rays;
      out.length.add(len);
      const MapPointLedger::Point* p = m.map_points().find(kfs[i].ids[j]);
      if (p != nullptr) ++(p->believed ? out.believed_ends : out.doubted_ends);
    }
    ++out.crossings;
    const double cx = g.index_to_coord(k[0]) - e.x, cy = g.index_to_coord(k[1]) - e.y,
                 cz = g.index_to_coord(k[2]) - e.z;
    out.past.add(std::sqrt(cx * cx + cy * cy + cz * cz));
    double nearest = std::numeric_limits<double>::infinity();
    for (const Point3d& q : believed[k.pack()]) {
      const double wx = q.x - o.x, wy = q.y - o.y, wz = q.z - o.z;
      const double t = (wx * dx + wy * dy + wz * dz) / (len * len);
      const double ax = wx - t * dx, ay = wy - t * dy, az = wz - t * dz;
      nearest = std::min(nearest, std::sqrt(ax * ax + ay * ay + az * az));
    }
    if (nearest < std::numeric_limits<double>::infinity()) out.aside.add(nearest);
  };
  eval::for_each_seen_through(mapper.map(), kfs, held, eval::heldout_points(kfs, held), opt, cross);
}

// The held-out contradictions the robust model leaves on a real set at a 0.3 m margin (5 folds,
// 4 m crop): its seen-through voxels, how many OctoMap's fold maps also have, the most-detected
// believed point in each, and the held-out rays through them (length, distance from the voxel's
// centre to the ray's point, how far from the believed points there it passes, whether the model
// believes its point).
void heldout_left(const std::string& dir, double res) {
  if (!std::filesystem::is_directory(dir)) return;
  const std::vector<eval::IdKeyframe> kfs = eval::id_keyframes(io::Sequence::open(dir), 4.0);
  eval::HeldoutOptions opt;
  opt.end_margin = 0.3;
  std::size_t left = 0, also_octomap = 0;
  Quartiles most_detected;
  RaysThrough rays;
  for (std::size_t f = 0; f < opt.folds; ++f) {
    const auto train = eval::fold_indices(kfs.size(), opt.folds, f, false);
    const auto held = eval::fold_indices(kfs.size(), opt.folds, f, true);
    Mapper<RobustModel> robust(res);
    Mapper<OctoMapModel> octomap(res);
    std::vector<Point3f> fl;
    for (const std::size_t i : train) {
      robust.insert_keyframe(kfs[i].origin, kfs[i].points, kfs[i].ids, kfs[i].evidence);
      fl.clear();
      for (const Point3d& p : kfs[i].points) fl.push_back(knnocc::detail::to_point3f(p));
      octomap.insert_keyframe(kfs[i].origin, fl);
    }
    std::vector<OcKey> st, st_octomap;
    eval::score_heldout(robust.map(), kfs, held, opt, &st);
    eval::score_heldout(octomap.map(), kfs, held, opt, &st_octomap);
    const std::unordered_set<OcKey, KeyHash> in_octomap(st_octomap.begin(), st_octomap.end());
    const RobustModel& m = robust.model();
    std::unordered_map<std::uint64_t, std::uint32_t> top;  // voxel -> most detections, believed
    m.map_points().for_each([&](std::uint64_t, const MapPointLedger::Point& p) {
      if (p.has_key && p.believed) top[p.key] = std::max(top[p.key], m.counts(p).d);
    });
    for (const OcKey& k : st) {
      ++left;
      also_octomap += in_octomap.count(k);
      most_detected.add(top.count(k.pack()) ? top[k.pack()] : 0);
    }
    rays_through(kfs, held, robust, opt, rays);
  }
  std::printf(
      "  held-out contradictions left at a 0.3 m margin (5 folds, 4 m crop): %zu voxels, %zu of "
      "them also in OctoMap's maps;\n    detections of the most-detected believed point in each "
      "%s (quartiles, range);\n    %zu held-out rays through them (%zu crossings), ending at a "
      "point the model believes %zu, doubts %zu, never saw %zu; length %s m;\n    per crossing, "
      "voxel centre to the ray's point %s m, ray to the nearest believed point in the voxel %s m\n",
      left, also_octomap, most_detected.with_range().c_str(), rays.rays, rays.crossings,
      rays.believed_ends, rays.doubted_ends, rays.rays - rays.believed_ends - rays.doubted_ends,
      rays.length.with_range().c_str(), rays.past.with_range().c_str(),
      rays.aside.with_range().c_str());
}

const char* const kUsage =
    "usage: build/bin/diag_robust_model [--seeds N] [--first-seed S] [--data DIR] [--repeat N]\n"
    "         [--cluster N] [--repeat-prob P]\n"
    "  what the robust model believes and why: the regimes on seeds S..S+N-1 (default 1..5,\n"
    "  their wrong patches changed as bench_robust_model changes them), then the real sets in\n"
    "  DIR (default ../shared/data)\n";

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
    else if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      return 0;
    } else {
      std::fprintf(stderr, "diag_robust_model: unknown or incomplete option %s\n%s", a.c_str(),
                   kUsage);
      return 2;
    }
  }
  std::printf("diag_robust_model: seeds %d..%d\n", first, first + seeds - 1);
  for (const sim::Regime& r : sim::named_regimes())
    if (r.name == "repeated" || r.name == "realistic")
      simulated(r, first, seeds, repeat, cluster, repeat_prob);
  real_set(data + "/orbslam2_stereo_keyframes", 0.1);
  heldout_left(data + "/orbslam2_stereo_keyframes", 0.1);
  real_set(data + "/icl_living_room_traj2n", 0.05);
  return 0;
}
