// Python's Mapper (one keyframe at a time, paper Alg. 3, any of the four models) and LiveMapper
// (keyframes added, re-posed and removed under SLAM corrections; the map stays exact).

#include <algorithm>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "binding.hpp"

namespace knnocc::python {

namespace {

struct MapperRef {
  std::shared_ptr<MapperOwner> owner;
  std::string model;
};
struct LiveRef {
  std::shared_ptr<LiveOwner> owner;
  std::string model;
};

double number(py::handle v) {
  const double x = PyFloat_AsDouble(v.ptr());
  if (x == -1.0 && PyErr_Occurred()) throw py::error_already_set();
  return x;
}

long long integer(py::handle v, const std::string& key, long long lo, long long hi) {
  if (!py::isinstance<py::int_>(v)) throw py::type_error(key + " must be an integer");
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(v.ptr(), &overflow);
  if (overflow || x < lo || x > hi)
    throw py::value_error(key + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                          "], got " + py::str(v).cast<std::string>());
  return x;
}

bool flag(py::handle v, const std::string& key) {
  if (!py::isinstance<py::bool_>(v)) throw py::type_error(key + " must be True or False");
  return v.cast<bool>();
}

constexpr const char* kCommon = "max_range, threads, clamp_min, clamp_max";
constexpr const char* kOctoMap = "prob_hit, prob_miss, discretize";
constexpr const char* kKnn = "k, w, p_upper, p_w, p_free, s_limit";
constexpr const char* kKnn2022 = "k, inner_range, p_near, p_far, p_miss, p_miss_outer, mu, sigma";

// One keyword argument of the 2022 model into p; false for a key it does not take.
bool knn2022_option(Knn2022Params& p, const std::string& key, py::handle v, bool& mu, bool& sigma) {
  if (key == "k")
    p.k = static_cast<std::size_t>(integer(v, key, 1, 4096));
  else if (key == "inner_range")
    p.inner_range = number(v);
  else if (key == "p_near")
    p.p_near = number(v);
  else if (key == "p_far")
    p.p_far = number(v);
  else if (key == "p_miss")
    p.p_miss = number(v);
  else if (key == "p_miss_outer")
    p.p_miss_outer = number(v);
  else if (key == "mu")
    p.mu = number(v), mu = true;
  else if (key == "sigma")
    p.sigma = number(v), sigma = true;
  else
    return false;
  return true;
}

// The keyword arguments of Mapper / LiveMapper for `model`; ValueError for a model or a
// parameter it does not take, TypeError for a value of the wrong type.
ModelOptions options_in(const char* cls, const std::string& model, const py::dict& kw, bool live) {
  const bool octomap = model == "octomap", knn = model == "knn", robust = model == "robust",
             knn2022 = model == "knn2022";
  if (!(octomap || knn || ((robust || knn2022) && !live)))
    throw py::value_error(std::string(cls) + ": model must be " +
                          (live ? "'octomap' or 'knn' (the live mapper takes neither the robust "
                                  "model nor the 2022 one)"
                                : "'octomap', 'knn', 'knn2022' or 'robust'") +
                          ", got '" + model + "'");
  ModelOptions o;
  double clamp_min = 0.1192, clamp_max = 0.971;
  bool mu = false, sigma = false;  // the 2022 model's fixed statistics: both or neither
  for (const auto& item : kw) {
    const std::string key = py::str(item.first);
    const py::handle v = item.second;
    if (key == "max_range")
      o.mapper.max_range = number(v);
    else if (key == "threads")
      o.mapper.threads = static_cast<unsigned>(integer(v, key, 1, 1024));
    else if (key == "clamp_min")
      clamp_min = number(v);
    else if (key == "clamp_max")
      clamp_max = number(v);
    else if (octomap && key == "prob_hit")
      o.prob_hit = number(v);
    else if (octomap && key == "prob_miss")
      o.prob_miss = number(v);
    else if (octomap && key == "discretize")
      o.mapper.discretize = flag(v, key);
    else if ((knn || robust) && key == "k")
      o.knn.k = static_cast<std::size_t>(integer(v, key, 1, 4096));
    else if ((knn || robust) && key == "w")
      o.knn.w = number(v);
    else if ((knn || robust) && key == "p_upper")
      o.knn.p_upper = number(v);
    else if ((knn || robust) && key == "p_w")
      o.knn.p_w = number(v);
    else if ((knn || robust) && key == "p_free")
      o.knn.p_free = number(v);
    else if ((knn || robust) && key == "s_limit")
      o.knn.s_limit = number(v);
    else if (robust && key == "margin_scale")
      o.margin_scale = number(v);
    else if (knn2022 && !knn2022_option(o.knn2022, key, v, mu, sigma))
      throw py::value_error(std::string(cls) + "(model='" + model + "'): unknown parameter '" +
                            key + "' (takes " + kCommon + ", " + kKnn2022 + ")");
    else if (!knn2022)
      throw py::value_error(std::string(cls) + "(model='" + model + "'): unknown parameter '" +
                            key + "' (takes " + kCommon + ", " + (octomap ? kOctoMap : kKnn) +
                            (robust ? ", margin_scale" : "") + ")");
  }
  if (mu != sigma)
    throw py::value_error(std::string(cls) +
                          "(model='knn2022'): mu and sigma go together (a first pass's "
                          "statistics; neither: running ones)");
  o.knn2022.fixed_statistics = mu;
  o.mapper.occupancy = occupancy_params(clamp_min, clamp_max);
  return o;
}

py::dict stats_out(const TrackerStats& s) {
  py::dict d;
  if (!s.kept) return d;
  d["k"] = s.k;
  d["map_points"] = s.map_points;
  d["valid"] = s.valid;
  d["mu"] = s.mu;
  d["sigma"] = s.sigma;
  return d;
}

py::object map_of(const std::shared_ptr<MapOwner>& owner) {
  return py::cast(MapRef{owner, nullptr});
}

// "Cls.member" for guards and messages, kept as long as the module (a guard keeps the name of
// the writer it lets in).
const char* member_name(const char* cls, const char* member) {
  static std::deque<std::string> names;
  return names.emplace_back(std::string(cls) + "." + member).c_str();
}

// What Mapper and LiveMapper have alike: map, model, statistics, memory_limit, repr.
template <class Ref>
void bind_owner_members(py::class_<Ref>& c, const char* cls, const char* models) {
  c.def_property_readonly(
      "map", [](const Ref& self) { return map_of(self.owner); },
      "The map, as an OccupancyMap that reads only (it follows its owner). A wide Mapper shows "
      "its map at OctoMap's keys, made when read after an insert (ValueError when it reaches "
      "beyond their range: write_tiles holds any map).");
  c.def_property_readonly(
      "model", [](const Ref& self) { return self.model; }, models);
  c.def(
      "statistics",
      [name = member_name(cls, "statistics")](const Ref& self) {
        const auto lock = self.owner->guard.read(name);
        return stats_out(self.owner->statistics());
      },
      "The k-NN statistics of the map point cloud: {'k', 'map_points', 'valid', 'mu', 'sigma'} "
      "(the tool's `knn` line); {} for the OctoMap model.");
  c.def_property(
      "memory_limit",
      [name = member_name(cls, "memory_limit")](const Ref& self) {
        const auto lock = self.owner->guard.read(name);
        return self.owner->memory_limit();
      },
      [name = member_name(cls, "memory_limit")](const Ref& self, const py::object& bytes) {
        const std::size_t limit = memory_limit_in(bytes);
        const auto lock = self.owner->guard.write(name);
        self.owner->set_memory_limit(limit);
      },
      "Bytes the map may use (0: no limit, the default); an insertion that would pass it raises "
      "MemoryError.");
  c.def("__repr__", [cls](const Ref& self) {
    return std::string("<knnocc.") + cls + " model '" + self.model + "'>";
  });
}

constexpr const char* kParamsDoc = R"(
Keyword parameters, by model (defaults in brackets):
  all models     max_range [-1: no limit]: points farther from the sensor free their ray up to
                 max_range and mark nothing (OctoMap's maxrange); threads [1]: threads that
                 walk the rays (the map is the same for every count); clamp_min [0.1192],
                 clamp_max [0.971]: OctoMap's clamping, as probabilities
  'octomap'      prob_hit [0.7], prob_miss [0.4], discretize [False]
  'knn'          k [8], w [0], p_upper [0.9], p_w [0.65], p_free [0.4], s_limit [inf]: the
                 paper's eq 13-15 (docs/library.md, "The k-NN model and the mapper")
  'robust'       the 'knn' parameters and margin_scale [2] (Mapper only)
  'knn2022'      k [24], inner_range [4], p_near [0.97], p_far [0.45], p_miss [0.4],
                 p_miss_outer [0.45]; mu and sigma: fixed statistics (Knn2022FirstPass), or
                 neither for running ones (Mapper only; give it whole clouds: it cuts at
                 inner_range itself)
ValueError for an unknown model or parameter, or a value out of range.)";

constexpr const char* kMapperDoc =
    R"(One keyframe at a time into an occupancy map (the paper's Alg. 3).

Mapper(resolution, model="octomap", *, wide=False, **params)

  model="octomap"  OctoMap's insertPointCloud, bit for bit (dense depth cameras, LiDAR)
  model="knn"      the paper's k-NN model: each point rated by its mean distance to its k
                   nearest map points (sparse visual-SLAM keyframes)
  model="robust"   beyond the paper: map points believed real under a mixture fitted to the
                   sequence (ORB-SLAM keyframes with map-point ids)
  model="knn2022"  the authors' 2022 model (Sensors 22(1):139), a baseline to compare with

  mapper = knnocc.Mapper(0.1, model="knn", k=8)
  for pose, points, ids in knnocc.read_sequence("keyframes"):
      mapper.insert_keyframe(pose[:3, 3], knnocc.to_world(pose, points), ids)
  mapper.map.write("map.bt")

The same calls as the knnocc tool's `map` command build the same map, byte for byte.
wide=True: 21-bit keys (+-2^20 voxels: +-104.9 km at 0.1 m, the tool's --key-bits 21) instead of
OctoMap's 16 bits (+-3.3 km at 0.1 m); inside OctoMap's range the same map, voxel for voxel.
write_tiles(path) writes any map as a tile set (docs/tiles.md).
)";

constexpr const char* kLiveDoc =
    R"(An occupancy map that follows a SLAM system's corrections exactly.

LiveMapper(resolution, model="octomap", **params)   (models 'octomap' and 'knn')

It owns the keyframes: add(keyframe_id, pose, points, ids=None) with `pose` a 4x4
sensor-to-world matrix and `points` in the sensor frame; repose({keyframe_id: pose}) after a
bundle adjustment or loop closure; remove(ids) for keyframe culling. After every call .map equals,
bit for bit, a Mapper over the current keyframes with their current poses (points moved by
knnocc.to_world). The OctoMap model replays only the keyframes that see the changed region; the
k-NN model rebuilds (its statistics change every later rating).
)";

// The rating pass of a run (knnocc.dask): as `knnocc map --out-tiles` rates the scans, into the
// folder `rated`; the run's totals and the model's statistics.
py::dict rate_sequence(const std::string& sequence, const std::string& rated, double resolution,
                       const std::string& model, int key_bits, double crop, bool world_points,
                       std::size_t first, const py::object& count, const py::kwargs& kw) {
  if (key_bits != 16 && key_bits != 21) throw py::value_error("key_bits must be 16 or 21");
  py::dict params;
  bool first_pass = model == "knn2022";
  for (const auto& item : kw) {
    const std::string key = py::str(item.first);
    if (key == "stats") {
      const std::string v = py::str(item.second);
      if (v != "first-pass" && v != "online")
        throw py::value_error("stats must be 'first-pass' or 'online', got '" + v + "'");
      first_pass = model == "knn2022" && v == "first-pass";
    } else {
      params[item.first] = item.second;
    }
  }
  if (params.contains("mu")) first_pass = false;  // the caller's statistics
  ModelOptions o = options_in("rate", model, params, false);
  const io::ScanSource source = io::ScanSource::open(sequence);
  if (first >= source.size()) throw py::value_error("first is past the sequence's end");
  const std::size_t last =
      count.is_none()
          ? source.size()
          : first + std::min<std::size_t>(count.cast<std::size_t>(), source.size() - first);
  std::vector<double> ms;
  tiles::RatingTotals t;
  TrackerStats stats;
  {
    const py::gil_scoped_release nogil;
    if (first_pass)
      o.knn2022 = knn2022_first_pass(source, o.knn2022, crop, world_points, first, last);
    o.knn2022.fixed_statistics = o.knn2022.fixed_statistics || first_pass;
    const bool wide = key_bits == 21;
    const std::shared_ptr<MapperOwner> mapper =
        model == "octomap"   ? make_octomap_mapper(resolution, o, wide)
        : model == "knn"     ? make_knn_mapper(resolution, o, wide)
        : model == "knn2022" ? make_knn2022_mapper(resolution, o, wide)
                             : make_robust_mapper(resolution, o, wide);
    t = mapper->rate_sequence(source, rated, crop, world_points, first, last, ms);
    stats = mapper->statistics();
  }
  py::dict d = stats_out(stats);
  d["clouds"] = t.clouds;
  d["points"] = t.points;
  d["nonfinite"] = t.nonfinite;
  d["out_of_range"] = t.out_of_range;
  d["rated"] = t.rated;
  d["rays"] = t.rays;
  d["first"] = first;
  std::sort(ms.begin(), ms.end());
  d["median_keyframe_ms"] = ms.empty() ? 0.0 : ms[ms.size() / 2];
  if (model == "knn2022") {
    d["mu"] = o.knn2022.mu;
    d["sigma"] = o.knn2022.sigma;
  }
  return d;
}

}  // namespace

void bind_mappers(py::module_& m) {
  m.def("_rate_sequence", &rate_sequence, py::arg("sequence"), py::arg("rated"),
        py::arg("resolution"), py::arg("model"), py::arg("key_bits") = 16, py::arg("crop") = -1.0,
        py::arg("world_points") = false, py::arg("first") = 0, py::arg("count") = py::none(),
        "For knnocc.dask: the rating pass of `knnocc map --out-tiles` into the folder `rated` "
        "(rated.txt and one .rkf per scan); the run's totals.");
  py::class_<MapperRef> mapper(m, "Mapper", (std::string(kMapperDoc) + kParamsDoc).c_str());
  mapper.def(py::init([](double resolution, const std::string& model, const py::object& wide_obj,
                         const py::kwargs& kw) {
               const bool wide = flag(wide_obj, "wide");
               const ModelOptions o = options_in("Mapper", model, kw, false);
               if (model == "octomap")
                 return MapperRef{make_octomap_mapper(resolution, o, wide), model};
               if (model == "knn") return MapperRef{make_knn_mapper(resolution, o, wide), model};
               if (model == "knn2022")
                 return MapperRef{make_knn2022_mapper(resolution, o, wide), model};
               return MapperRef{make_robust_mapper(resolution, o, wide), model};
             }),
             py::arg("resolution"), py::arg("model") = "octomap", py::kw_only(),
             py::arg("wide") = false,
             "A new mapper with an empty map; see help(knnocc.Mapper) for the parameters.");
  mapper.def_property_readonly(
      "wide", [](const MapperRef& self) { return self.owner->wide(); },
      "Whether the map has 21-bit keys (Mapper(..., wide=True)).");
  mapper.def(
      "write_tiles",
      [](const MapperRef& self, const py::object& path_obj, int tile_depth) {
        const std::string path = path_in(path_obj);
        const auto lock = self.owner->guard.read("Mapper.write_tiles");
        const py::gil_scoped_release nogil;
        return self.owner->write_tiles(path, tile_depth);
      },
      py::arg("path"), py::arg("tile_depth") = 6,
      R"(Writes the map as a tile set in the folder `path` (new or empty, or an earlier tile set,
replaced): one OctoMap .ot per tile of 2^(16 - tile_depth) voxels per edge and an index
(docs/tiles.md); returns the number of tiles. Any extent, wide or not: `knnocc merge path -o
map.bt` joins it into one file where it fits OctoMap's key range, and `knnocc view` / `info` /
`convert` read it as it is.)");
  mapper.def(
      "insert_keyframe",
      [](const MapperRef& self, const py::object& origin, const py::object& points,
         const py::object& ids, const py::object& evidence) {
        const Point3d o = vec3_in(origin, "origin");
        const PointsIn in(points, "points", limit_of(*self.owner, "Mapper.insert_keyframe"));
        const std::vector<std::uint64_t> id = ids_in(ids, in.size(), "ids");
        const std::vector<PointEvidence> ev = evidence_in(evidence, in.size(), "evidence");
        const auto lock = self.owner->guard.write("Mapper.insert_keyframe");
        const py::gil_scoped_release nogil;
        self.owner->insert_keyframe(o, in.view(), id, ev);
      },
      py::arg("origin"), py::arg("points"), py::arg("ids") = py::none(),
      py::arg("evidence") = py::none(),
      R"(Alg. 3 for one keyframe: `points` (N, 3) in the world frame seen from `origin` (the sensor
position, 3 numbers); `ids` one map-point id per point (e.g. ORB-SLAM's MapPoint::mnId) or None.
The map point cloud is the union of the keyframes' points: an id joins once, at its first
position; without ids every point is a new map point. A sequence gives ids always or never
(ValueError otherwise). The OctoMap and 2022 models ignore ids. `evidence`: None or (N, 3)
integers, the SLAM system's found, visible and observations counts per point
(Sequence.evidence(i) reads them from PLY clouds), which the robust model uses; the others ignore
them. MemoryError past memory_limit.)");
  bind_owner_members(mapper, "Mapper", "'octomap', 'knn', 'knn2022' or 'robust'.");
  refuse_uninitialised(mapper);

  py::class_<LiveRef> live(m, "LiveMapper", (std::string(kLiveDoc) + kParamsDoc).c_str());
  live.def(py::init([](double resolution, const std::string& model, const py::kwargs& kw) {
             const ModelOptions o = options_in("LiveMapper", model, kw, true);
             if (model == "octomap") return LiveRef{make_octomap_live(resolution, o), model};
             return LiveRef{make_knn_live(resolution, o), model};
           }),
           py::arg("resolution"), py::arg("model") = "octomap",
           "A new live mapper without keyframes; see help(knnocc.LiveMapper) for the parameters.");
  live.def(
      "add",
      [](const LiveRef& self, const py::object& keyframe_id, const py::object& pose,
         const py::object& points, const py::object& ids) {
        const std::uint64_t id = id_in(keyframe_id, "keyframe_id");
        const Pose p = pose_in(pose, "pose");
        const PointsIn in(points, "points", limit_of(*self.owner, "LiveMapper.add"));
        std::vector<std::uint64_t> map_ids = ids_in(ids, in.size(), "ids");
        const auto lock = self.owner->guard.write("LiveMapper.add");
        const py::gil_scoped_release nogil;
        std::vector<Point3f> sensor(in.size());
        in.view().visit([&](const auto& span) {
          for (std::size_t i = 0; i < span.size(); ++i) sensor[i] = as_float(span[i]);
        });
        self.owner->add(id, p, std::move(sensor), std::move(map_ids));
      },
      py::arg("keyframe_id"), py::arg("pose"), py::arg("points"), py::arg("ids") = py::none(),
      R"(Adds keyframe `keyframe_id` (a new non-negative integer): `pose` a 4x4 sensor-to-world
matrix, `points` (N, 3) in the sensor frame (kept as float32), `ids` one map-point id per point
or None (k-NN model: always or never). ValueError for a known id or a bad pose.)");
  live.def(
      "repose",
      [](const LiveRef& self, const py::dict& poses) {
        std::vector<std::pair<std::uint64_t, Pose>> list;
        for (const auto& item : poses)
          list.emplace_back(id_in(item.first, "keyframe id"), pose_in(item.second, "pose"));
        const auto lock = self.owner->guard.write("LiveMapper.repose");
        const py::gil_scoped_release nogil;
        self.owner->repose(list);
      },
      py::arg("poses"),
      "Re-poses keyframes at once: {keyframe_id: 4x4 pose} (a local bundle adjustment, a loop "
      "closure). Poses equal to the stored ones change nothing. ValueError, with nothing "
      "changed, for an unknown id.");
  live.def(
      "remove",
      [](const LiveRef& self, const py::iterable& ids) {
        std::vector<std::uint64_t> list;
        for (const py::handle id : ids) list.push_back(id_in(id, "keyframe id"));
        const auto lock = self.owner->guard.write("LiveMapper.remove");
        const py::gil_scoped_release nogil;
        self.owner->remove(list);
      },
      py::arg("ids"),
      "Removes keyframes (keyframe culling). ValueError, with nothing changed, for an unknown id.");
  live.def(
      "__len__",
      [](const LiveRef& self) {
        const auto lock = self.owner->guard.read("LiveMapper.__len__");
        return self.owner->size();
      },
      "The number of keyframes.");
  live.def(
      "__contains__",
      [](const LiveRef& self, const py::object& id) {
        // Like a set: what cannot be a keyframe id (not an integer, negative, 2**64 or more) is
        // not held.
        const U64 v = u64_of(id, true);
        if (v.kind != U64::ok) return false;
        const auto lock = self.owner->guard.read("LiveMapper.__contains__");
        return self.owner->contains(v.value);
      },
      py::arg("keyframe_id"), "Whether the keyframe is held.");
  live.def_property_readonly(
      "last_update",
      [](const LiveRef& self) {
        const auto lock = self.owner->guard.read("LiveMapper.last_update");
        const LiveUpdate u = self.owner->last_update();
        py::dict d;
        d["changed"] = u.changed;
        d["replayed"] = u.replayed;
        d["bricks"] = u.bricks;
        d["rebuilt"] = u.rebuilt;
        return d;
      },
      "What the last add / repose / remove did: {'changed': keyframes added, re-posed or removed, "
      "'replayed': keyframes whose rays were cast again, 'bricks': map bricks recomputed by a "
      "regional replay, 'rebuilt': the map was built again from scratch}.");
  bind_owner_members(live, "LiveMapper", "'octomap' or 'knn'.");
  refuse_uninitialised(live);
}

}  // namespace knnocc::python
