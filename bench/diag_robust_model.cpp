// diag_robust_model: what the robust model (sensor/robust_model.hpp) keeps that it should not,
// and what it loses. Prints, for the simulator's repeated and realistic regimes (seeds 1..N; the
// model without temporal consistency and lone points, then the defaults), the
// observation geometry of the map points that commit evidence (wrong patches against real
// points: views, keyframe span, angle spread between their viewing rays, what supports them) and,
// on the real stereo keyframes (0.1 m, 4 m crop), the same for the points in isolated and in lost
// multi-view voxels against the OctoMap model's map.
//
//   build/bin/diag_robust_model [--seeds N] [--data DIR]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/multiview.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

using namespace knnocc;

namespace {

// Every observation of every map point: keyframe index and camera position.
struct Track {
  Point3d pos;
  std::vector<std::uint32_t> kf;
  std::vector<Point3d> origin;
  std::uint32_t views() const { return static_cast<std::uint32_t>(kf.size()); }
  // largest angle (deg) between two viewing rays among the first n observations
  double spread(std::size_t n) const {
    n = std::min(n, kf.size());
    double best = 0;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b) {
        const double ax = origin[a].x - pos.x, ay = origin[a].y - pos.y, az = origin[a].z - pos.z;
        const double bx = origin[b].x - pos.x, by = origin[b].y - pos.y, bz = origin[b].z - pos.z;
        const double c = (ax * bx + ay * by + az * bz) /
                         std::sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz));
        best = std::max(best, std::acos(std::clamp(c, -1.0, 1.0)) * 180 / M_PI);
      }
    return best;
  }
  std::uint32_t span(std::size_t n) const {
    n = std::min(n, kf.size());
    return n ? kf[n - 1] - kf[0] : 0;
  }
};
using Tracks = std::unordered_map<std::uint64_t, Track>;

void add_keyframe(Tracks& t, std::uint32_t k, const Point3d& o, const std::vector<Point3d>& w,
                  const std::vector<std::uint64_t>& ids) {
  for (std::size_t j = 0; j < w.size(); ++j) {
    Track& tr = t[ids[j]];
    if (tr.kf.empty()) tr.pos = w[j];
    if (!tr.kf.empty() && tr.kf.back() == k) continue;
    tr.kf.push_back(k);
    tr.origin.push_back(o);
  }
}

struct Quant {
  std::vector<double> v;
  void add(double x) { v.push_back(x); }
  void print(const char* name) {
    std::sort(v.begin(), v.end());
    if (v.empty()) {
      std::printf("    %-26s n=0\n", name);
      return;
    }
    auto q = [&](double f) { return v[std::min(v.size() - 1, std::size_t(f * double(v.size())))]; };
    std::printf("    %-26s n=%6zu  p10 %6.1f p25 %6.1f p50 %6.1f p75 %6.1f p90 %6.1f\n", name,
                v.size(), q(0.1), q(0.25), q(0.5), q(0.75), q(0.9));
  }
};

struct Group {
  Quant views, span3, spread3, spread_all, span_all;
  void add(const Track& t) {
    views.add(t.views());
    span3.add(t.span(3));
    spread3.add(t.spread(3));
    span_all.add(t.span(t.kf.size()));
    spread_all.add(t.spread(t.kf.size()));
  }
  void print(const char* title) {
    std::printf("  %s\n", title);
    views.print("views");
    span3.print("keyframe span of 3 views");
    span_all.print("keyframe span, all views");
    spread3.print("angle spread 3 views (deg)");
    spread_all.print("angle spread all (deg)");
  }
};

void simulator(int seeds, const RobustModelParams& params, const char* label) {
  for (const sim::Regime& regime : sim::named_regimes()) {
    if (regime.name != "repeated" && regime.name != "realistic") continue;
    Group wrong_irrel, wrong_other, real;
    std::size_t irrel = 0, irrel_wrong = 0, wrong_commit = 0, wrong_pts = 0, sup_real = 0,
                sup_wrong_only = 0, consec = 0, real_consec = 0, real_commit = 0;
    for (int s = 1; s <= seeds; ++s) {
      sim::TreeSceneParams p = regime.params;
      p.seed = static_cast<std::uint64_t>(s);
      sim::TreeScene scene(p);
      const auto kfs = scene.keyframes();
      Tracks tracks;
      Mapper<RobustModel> mapper(0.1, RobustModel(params));
      std::vector<Point3d> w;
      std::vector<std::uint64_t> ids;
      for (std::size_t i = 0; i < kfs.size(); ++i) {
        io::keyframe_to_world(kfs[i].pose, kfs[i].cloud, 4.0, w, ids);
        const Point3d o{kfs[i].pose.t.x(), kfs[i].pose.t.y(), kfs[i].pose.t.z()};
        add_keyframe(tracks, static_cast<std::uint32_t>(i), o, w, ids);
        mapper.insert_keyframe(o, w, ids);
      }
      const auto& map = mapper.map();
      const auto& g = map.grid();
      const double mu = mapper.tracker().distribution().mean();
      // irrelevant occupied voxels
      std::unordered_set<OcKey, KeyHash> irr;
      map.for_each_voxel([&](const OcKey& k, float v) {
        if (!map.is_occupied(v)) return;
        const Point3d c{g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2])};
        if (c.z < 0.3) return;
        if (scene.reference().distance(c) > 0.3) irr.insert(k);
      });
      irrel += irr.size();
      std::unordered_set<OcKey, KeyHash> irr_wrong;
      std::vector<std::pair<std::uint64_t, const MapPointLedger::Point*>> committed;
      mapper.model().map_points().for_each([&](std::uint64_t id, const auto& e) {
        if (e.added != 0.0f && !e.rejected) committed.push_back({id, &e});
      });
      for (const auto& [id, e] : committed) {
        const bool wrong = id >= sim::TreeScene::kOutlierIdBase;
        const Track& t = tracks.at(id);
        if (!wrong) {
          real.add(t);
          ++real_commit;
          real_consec += t.span(t.kf.size()) <= 4;
          continue;
        }
        ++wrong_commit;
        consec += t.span(t.kf.size()) <= 4;
        if (irr.count(OcKey::unpack(e->key))) {
          irr_wrong.insert(OcKey::unpack(e->key));
          wrong_irrel.add(t);
          ++wrong_pts;
          // its supporters within the support radius created by another keyframe
          bool any_real = false, any = false;
          const double r = params.support_scale * mu;
          for (const auto& [id2, t2] : tracks) {
            if (id2 == id || t2.kf[0] == t.kf[0]) continue;
            const double dx = t2.pos.x - t.pos.x, dy = t2.pos.y - t.pos.y, dz = t2.pos.z - t.pos.z;
            if (dx * dx + dy * dy + dz * dz > r * r) continue;
            any = true;
            any_real |= id2 < sim::TreeScene::kOutlierIdBase;
          }
          sup_real += any_real;
          sup_wrong_only += any && !any_real;
        } else {
          wrong_other.add(t);
        }
      }
      irrel_wrong += irr_wrong.size();
    }
    std::printf("\nregime %s, seeds 1..%d, robust model (%s)\n", regime.name.c_str(), seeds, label);
    std::printf(
        "  irrelevant voxels %zu, holding a committed wrong point %zu; committed wrong points %zu "
        "(%zu in irrelevant voxels; all views within 5 consecutive keyframes: %zu), committed real "
        "points %zu (within 5 consecutive: %zu)\n",
        irrel, irrel_wrong, wrong_commit, wrong_pts, consec, real_commit, real_consec);
    std::printf(
        "  wrong points in irrelevant voxels supported by a real point %zu, by other wrong points "
        "only %zu (within %g mu, another creator, final cloud)\n",
        sup_real, sup_wrong_only, params.support_scale);
    wrong_irrel.print("committed wrong points in irrelevant voxels:");
    wrong_other.print("committed wrong points elsewhere:");
    real.print("committed real points:");
  }
}

void real_set(const std::string& dir) {
  const io::Sequence seq = io::Sequence::open(dir);
  Tracks tracks;
  Mapper<RobustModel> rob(0.1, RobustModel{});
  Mapper<OctoMapModel> octo(0.1);
  eval::MapPointViews views;
  std::vector<Point3d> w;
  std::vector<Point3f> wf;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), 4.0, w, ids);
    const Point3d o{seq.pose(i).t.x(), seq.pose(i).t.y(), seq.pose(i).t.z()};
    add_keyframe(tracks, static_cast<std::uint32_t>(i), o, w, ids);
    views.add_keyframe(w, ids);
    rob.insert_keyframe(o, w, ids);
    wf.clear();
    for (const Point3d& p : w) wf.push_back(Point3f{float(p.x), float(p.y), float(p.z)});
    octo.insert_keyframe(o, wf);
  }
  const auto& rm = rob.map();
  const auto& om = octo.map();
  auto occ = [](const OccupancyMap<OcKey>& m, const OcKey& k) {
    const auto v = m.logodds(k);
    return v && m.is_occupied(*v);
  };
  auto isolated = [&](const OccupancyMap<OcKey>& m, const OcKey& k) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          OcKey n;
          if ((dx || dy || dz) && shifted_key(k, dx, dy, dz, n) && occ(m, n)) return false;
        }
    return true;
  };
  // points per voxel
  std::unordered_map<OcKey, std::vector<std::uint64_t>, KeyHash> in_voxel;
  for (const auto& [id, t] : tracks) {
    OcKey k;
    if (rm.grid().point_to_key(t.pos, k)) in_voxel[k].push_back(id);
  }
  auto max_views = [&](const OcKey& k) {
    std::uint32_t v = 0;
    for (auto id : in_voxel[k]) v = std::max(v, tracks.at(id).views());
    return v;
  };
  std::size_t iso = 0, iso_in_octo = 0, iso_mv = 0, iso_mv_octo_iso = 0, iso_nbr_lost = 0;
  Group iso_pts, ok_pts;
  std::unordered_set<OcKey, KeyHash> lost;
  for (const OcKey& k : views.multiview_voxels(rm.grid(), 3))
    if (occ(om, k) && !occ(rm, k)) lost.insert(k);
  rm.for_each_voxel([&](const OcKey& k, float v) {
    if (!rm.is_occupied(v)) return;
    const bool mv = max_views(k) >= 3;
    const auto* vec = &in_voxel[k];
    if (!isolated(rm, k)) {
      for (auto id : *vec) {
        const auto* e = rob.model().map_points().find(id);
        if (e && e->added != 0.0f) ok_pts.add(tracks.at(id));
      }
      return;
    }
    ++iso;
    iso_in_octo += isolated(om, k);
    iso_mv += mv;
    iso_mv_octo_iso += mv && isolated(om, k);
    bool nl = false;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          OcKey n;
          nl |= shifted_key(k, dx, dy, dz, n) && lost.count(n) > 0;
        }
    iso_nbr_lost += nl;
    for (auto id : *vec) {
      const auto* e = rob.model().map_points().find(id);
      if (e && e->added != 0.0f) iso_pts.add(tracks.at(id));
    }
  });
  std::printf("\nreal stereo keyframes (%zu, 0.1 m, 4 m crop), robust model (defaults)\n",
              seq.size());
  std::printf(
      "  isolated %zu: isolated in the OctoMap model's map too %zu; multi-view voxels %zu (of "
      "those isolated in OctoMap's too %zu); next to a lost multi-view voxel %zu\n",
      iso, iso_in_octo, iso_mv, iso_mv_octo_iso, iso_nbr_lost);
  iso_pts.print("committed points in isolated voxels:");
  ok_pts.print("committed points in non-isolated voxels:");
  // the lost multi-view voxels
  std::size_t never = 0, committed_free = 0;
  Group lost_pts;
  std::printf("  lost multi-view voxels %zu:\n", lost.size());
  for (const OcKey& k : lost) {
    bool any_commit = false;
    const auto lv = rm.logodds(k);
    std::printf("    voxel log-odds %6.2f:", lv ? double(*lv) : std::nan(""));
    for (auto id : in_voxel[k]) {
      const auto* e = rob.model().map_points().find(id);
      const Track& t = tracks.at(id);
      if (t.views() >= 3) lost_pts.add(t);
      any_commit |= e && e->added != 0.0f;
      std::printf(" [v%u span%u spr%.0f add%.2f]", t.views(), t.span(t.kf.size()),
                  t.spread(t.kf.size()), e ? double(e->added) : 0.0);
    }
    std::printf("\n");
    never += !any_commit;
    committed_free += any_commit;
  }
  std::printf("  lost: no point committed %zu, committed but not occupied %zu\n", never,
              committed_free);
  // The conflict between the two proxies: isolated voxels that are multi-view voxels occupied in
  // the OctoMap model's map count as lost once removed.
  std::size_t iso_mv_octo = 0;
  rm.for_each_voxel([&](const OcKey& k, float v) {
    if (rm.is_occupied(v) && isolated(rm, k) && max_views(k) >= 3 && occ(om, k)) ++iso_mv_octo;
  });
  const std::size_t budget = (2 * views.multiview_voxels(rm.grid(), 3).size()) / 100;
  std::size_t octo_isolated = 0;
  om.for_each_voxel(
      [&](const OcKey& k, float v) { octo_isolated += om.is_occupied(v) && isolated(om, k); });
  const std::size_t target = octo_isolated / 2;  // the goal: half the OctoMap model's
  std::printf(
      "  isolated voxels that are multi-view and occupied in the OctoMap model's map: %zu of %zu; "
      "removing isolated voxels only, reaching <= %zu isolated costs at least %zu more lost "
      "(lost %zu, budget %zu)\n",
      iso_mv_octo, iso, target,
      iso > target ? (iso - target > iso - iso_mv_octo ? iso - target - (iso - iso_mv_octo) : 0)
                   : 0,
      lost.size(), budget);
  // Temporal signature: multi-view voxels (occupied by OctoMap's model) all of whose multi-view
  // points were seen only within 5 consecutive keyframes (the simulator's wrong patches' span).
  std::size_t short_only = 0, mv_octo = 0, short_pts = 0, mv_pts = 0;
  for (const OcKey& k : views.multiview_voxels(rm.grid(), 3)) {
    if (!occ(om, k)) continue;
    ++mv_octo;
    bool all_short = true;
    for (auto id : in_voxel[k]) {
      const Track& t = tracks.at(id);
      if (t.views() < 3) continue;
      ++mv_pts;
      const bool sh = t.span(t.kf.size()) <= 4;
      short_pts += sh;
      all_short &= sh;
    }
    short_only += all_short;
  }
  std::printf(
      "  multi-view points seen only within 5 consecutive keyframes: %zu of %zu; multi-view "
      "voxels (occupied by OctoMap's model) holding only such points: %zu of %zu\n",
      short_pts, mv_pts, short_only, mv_octo);
  lost_pts.print("multi-view points in lost voxels:");
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5;
  std::string data = "../shared/data";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc)
      seeds = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--data") && i + 1 < argc)
      data = argv[++i];
  }
  RobustModelParams support_only;  // without temporal consistency and lone points
  support_only.min_span = 0;
  support_only.lone_span = 0;
  simulator(std::max(seeds, 1), support_only, "support only: min_span 0, lone_span 0");
  simulator(std::max(seeds, 1), RobustModelParams{}, "defaults");
  const std::string stereo = data + "/orbslam2_stereo_keyframes";
  if (std::filesystem::is_directory(stereo)) real_set(stereo);
  return 0;
}
