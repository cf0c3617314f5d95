// Python's OccupancyMap: insertion, point queries, voxels, .bt/.ot files and bytes, pickling,
// ray casts; read_map and cast_ray at module level.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/map/same_voxels.hpp>
#include <knnocc/raycast/cast_ray.hpp>

#include "binding.hpp"

namespace knnocc::python {

namespace {

py::object wrap(std::shared_ptr<MapObject> object) { return py::cast(MapRef{object, object}); }

Point3d centre(const Map& map, const OcKey& k) {
  const auto& g = map.grid();
  return {g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2])};
}

// One T per point, value(map, log-odds or nullopt) of the voxel holding it (unknown outside the
// key range), in an array of the points' outer shape.
template <class T, class F>
py::array_t<T> per_point(const MapRef& self, const py::object& points, const char* what,
                         F&& value) {
  const PointsIn in(points, "points");
  py::array_t<T> out(in.outer_shape());
  T* o = out.mutable_data();
  const auto lock = self.owner->guard.read(what);
  {
    const py::gil_scoped_release nogil;
    const Map& map = self.owner->map();
    in.view().visit([&](const auto& span) {
      OcKey key;
      for (std::size_t i = 0; i < span.size(); ++i)
        o[i] = value(map, map.grid().point_to_key(span[i], key) ? map.logodds(key) : std::nullopt);
    });
  }
  return out;
}

py::array_t<std::int8_t> occupancy_at(const MapRef& self, const py::object& points) {
  return per_point<std::int8_t>(
      self, points, "OccupancyMap.occupancy_at", [](const Map& map, std::optional<float> v) {
        return v ? static_cast<std::int8_t>(map.is_occupied(*v)) : std::int8_t{-1};
      });
}

py::array_t<float> logodds_at(const MapRef& self, const py::object& points) {
  return per_point<float>(self, points, "OccupancyMap.logodds_at",
                          [](const Map&, std::optional<float> v) {
                            return v ? *v : std::numeric_limits<float>::quiet_NaN();
                          });
}

enum class Which { occupied, free, all };
Which which_in(const std::string& which) {
  if (which == "occupied") return Which::occupied;
  if (which == "free") return Which::free;
  if (which == "all") return Which::all;
  throw py::value_error("which must be 'occupied', 'free' or 'all', got '" + which + "'");
}

py::tuple voxels(const MapRef& self, const std::string& which_text) {
  const Which which = which_in(which_text);
  std::vector<Point3d> centres;
  std::vector<float> values;
  {
    const auto lock = self.owner->guard.read("OccupancyMap.voxels");
    const py::gil_scoped_release nogil;
    const Map& map = self.owner->map();
    map.for_each_voxel([&](const OcKey& k, float v) {
      if (which != Which::all && map.is_occupied(v) != (which == Which::occupied)) return;
      centres.push_back(centre(map, k));
      values.push_back(v);
    });
  }
  const auto n = static_cast<py::ssize_t>(values.size());
  return py::make_tuple(adopt<double>(std::move(centres), {n, 3}),
                        adopt<float>(std::move(values), {n}));
}

py::tuple extract_point_cloud(const MapRef& self) {
  std::vector<Point3d> occupied, free;
  {
    const auto lock = self.owner->guard.read("OccupancyMap.extract_point_cloud");
    const py::gil_scoped_release nogil;
    const Map& map = self.owner->map();
    map.for_each_voxel([&](const OcKey& k, float v) {
      (map.is_occupied(v) ? occupied : free).push_back(centre(map, k));
    });
  }
  const auto n_occ = static_cast<py::ssize_t>(occupied.size());
  const auto n_free = static_cast<py::ssize_t>(free.size());
  return py::make_tuple(adopt<double>(std::move(occupied), {n_occ, 3}),
                        adopt<double>(std::move(free), {n_free, 3}));
}

std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

void write(const MapRef& self, const py::object& path_obj) {
  const std::string path = path_in(path_obj);
  const std::string ext = lower_extension(path);
  if (ext != ".bt" && ext != ".ot")
    throw py::value_error("write: " + path + ": the name must end in .bt or .ot");
  const auto lock = self.owner->guard.read("OccupancyMap.write");
  const py::gil_scoped_release nogil;
  if (ext == ".bt")
    io::write_bt(path, self.owner->map());
  else
    io::write_ot(path, self.owner->map());
}

py::bytes to_bytes(const MapRef& self, const std::string& format) {
  if (format != "bt" && format != "ot")
    throw py::value_error("format must be 'bt' or 'ot', got '" + format + "'");
  const auto lock = self.owner->guard.read("OccupancyMap.to_bytes");
  return py::bytes(without_gil([&] {
    return format == "bt" ? io::encode_bt(self.owner->map()) : io::encode_ot(self.owner->map());
  }));
}

Point3f point_at(const PointsView& v, std::size_t i) {
  return v.visit([&](const auto& span) { return as_float(span[i]); });
}

py::tuple cast_ray(const MapRef& self, const py::object& origin, const py::object& direction,
                   double max_range, bool ignore_unknown) {
  const PointsIn o(origin, "origin"), d(direction, "direction");
  const std::size_t n = std::max(o.size(), d.size());
  if ((o.size() != 1 && o.size() != n) || (d.size() != 1 && d.size() != n))
    throw py::value_error("cast_ray: " + std::to_string(o.size()) + " origins for " +
                          std::to_string(d.size()) +
                          " directions (one of each, one origin for N directions, or N of each)");
  py::array_t<bool> hits(static_cast<py::ssize_t>(n));
  py::array_t<double> ends({static_cast<py::ssize_t>(n), py::ssize_t{3}});
  bool* h = hits.mutable_data();
  double* e = ends.mutable_data();
  std::size_t bad = n;
  {
    const auto lock = self.owner->guard.read("OccupancyMap.cast_ray");
    const py::gil_scoped_release nogil;
    const Map& map = self.owner->map();
    for (std::size_t i = 0; i < n; ++i) {
      const Point3f dir = point_at(d.view(), d.size() == 1 ? 0 : i);
      const auto r = knnocc::cast_ray(map, point_at(o.view(), o.size() == 1 ? 0 : i), dir,
                                      ignore_unknown, max_range);
      // A zero direction is refused even where the walk would stop in the origin's voxel.
      if (r.status == CastStatus::invalid ||
          !(std::isfinite(dir.x) && std::isfinite(dir.y) && std::isfinite(dir.z)) ||
          (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f)) {
        bad = i;
        break;
      }
      h[i] = r.hit();
      const Point3d c = centre(map, r.key);
      e[3 * i] = c.x;
      e[3 * i + 1] = c.y;
      e[3 * i + 2] = c.z;
    }
  }
  if (bad < n)
    throw py::value_error("cast_ray: ray " + std::to_string(bad) +
                          ": the origin is not finite or outside the map's key range, or the "
                          "direction is zero or not finite");
  if (o.outer_shape().empty() && d.outer_shape().empty())
    return py::make_tuple(static_cast<bool>(h[0]), ends.attr("reshape")(3));
  return py::make_tuple(hits, ends);
}

// Pickle state (version 2): the format number, the resolution, the model's probabilities, the
// clamping and threshold in log-odds (exact), the memory limit, the number of voxels, every known
// voxel's key (3 x uint16) and log-odds (float32) as bytes, and the CRC-32 of those bytes (a
// state cut short or damaged in transit is refused, not loaded in part). Version 1, without the
// count and the CRC, is still read.
constexpr int kStateVersion = 2;

py::object get_state(const MapRef& self) {
  std::vector<std::uint16_t> keys;
  std::vector<float> values;
  const auto lock = self.owner->guard.read("OccupancyMap.__getstate__");
  const Map& map = self.owner->map();
  {
    const py::gil_scoped_release nogil;
    keys.reserve(3 * map.num_voxels());
    values.reserve(map.num_voxels());
    map.for_each_voxel([&](const OcKey& k, float v) {
      keys.insert(keys.end(), {k[0], k[1], k[2]});
      values.push_back(v);
    });
  }
  const OccupancyParams& p = map.params();
  const py::bytes key_bytes(reinterpret_cast<const char*>(keys.data()),
                            keys.size() * sizeof(keys[0]));
  const py::bytes value_bytes(reinterpret_cast<const char*>(values.data()),
                              values.size() * sizeof(float));
  const py::object crc32 = py::module_::import("zlib").attr("crc32");
  return py::make_tuple(kStateVersion, map.resolution(),
                        self.object ? self.object->prob_hit() : 0.7,
                        self.object ? self.object->prob_miss() : 0.4, p.clamp_min, p.clamp_max,
                        p.occupancy_threshold, map.memory_limit(), values.size(), key_bytes,
                        value_bytes, crc32(value_bytes, crc32(key_bytes)));
}

[[noreturn]] void bad_state(const std::string& problem) {
  throw py::value_error("OccupancyMap.__setstate__: " + problem);
}

// Item `i` of a state, a finite real number.
double state_number(const py::tuple& t, std::size_t i, const char* name) {
  const py::handle v = t[i];
  if (!(py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)) ||
      py::isinstance<py::bool_>(v))
    bad_state(std::string(name) + " must be a number, got " +
              py::str(py::type::of(v).attr("__name__")).cast<std::string>());
  const double x = PyFloat_AsDouble(v.ptr());  // an integer beyond double's range: OverflowError
  if (PyErr_Occurred()) {
    PyErr_Clear();
    bad_state(std::string(name) + " must be finite");
  }
  if (!std::isfinite(x)) bad_state(std::string(name) + " must be finite");
  return x;
}

// Item `i` of a state, an integer in [0, 2^64).
std::size_t state_count(const py::tuple& t, std::size_t i, const char* name) {
  const U64 v = u64_of(t[i], false);
  if (v.kind == U64::not_integer || v.kind == U64::negative)
    bad_state(std::string(name) + " must be a non-negative integer");
  if (v.kind == U64::too_large) bad_state(std::string(name) + " must be below 2**64");
  return v.value;
}

MapRef set_state(const py::object& state) {
  if (!py::isinstance<py::tuple>(state))
    bad_state("not a pickled knnocc map (the state is not a tuple)");
  const auto t = py::reinterpret_borrow<py::tuple>(state);
  const std::size_t size = t.size();
  const py::handle version = size ? t[0] : py::handle();
  if (!version || !py::isinstance<py::int_>(version) || py::isinstance<py::bool_>(version) ||
      !((version.cast<py::int_>().equal(py::int_(1)) && size == 10) ||
        (version.cast<py::int_>().equal(py::int_(kStateVersion)) && size == 12)))
    bad_state("not a pickled knnocc map of state version 1 (10 items) or 2 (12 items)");
  const bool v1 = size == 10;
  const double resolution = state_number(t, 1, "resolution");
  const double prob_hit = state_number(t, 2, "prob_hit"),
               prob_miss = state_number(t, 3, "prob_miss");
  OccupancyParams p;
  p.clamp_min = static_cast<float>(state_number(t, 4, "clamp_min"));
  p.clamp_max = static_cast<float>(state_number(t, 5, "clamp_max"));
  p.occupancy_threshold = static_cast<float>(state_number(t, 6, "occupancy_threshold"));
  const std::size_t memory_limit = state_count(t, 7, "memory_limit");
  const std::size_t keys_at = v1 ? 8 : 9;
  for (std::size_t i : {keys_at, keys_at + 1})
    if (!py::isinstance<py::bytes>(t[i]))
      bad_state(std::string(i == keys_at ? "the keys" : "the log-odds") + " must be bytes");
  const auto keys = t[keys_at].cast<std::string_view>();
  const auto values = t[keys_at + 1].cast<std::string_view>();
  const std::size_t n = v1 ? values.size() / sizeof(float) : state_count(t, 8, "the voxel count");
  // Compared by division: a count near 2^64 must not wrap round to the bytes' size.
  if (values.size() % sizeof(float) != 0 || values.size() / sizeof(float) != n ||
      keys.size() % (3 * sizeof(std::uint16_t)) != 0 ||
      keys.size() / (3 * sizeof(std::uint16_t)) != n)
    bad_state(std::to_string(keys.size()) + " bytes of keys and " + std::to_string(values.size()) +
              " of log-odds for " + std::to_string(n) +
              " voxels (6 and 4 each): the state is cut short or damaged");
  if (!v1) {
    const py::object crc32 = py::module_::import("zlib").attr("crc32");
    if (!py::isinstance<py::int_>(t[11]) || py::isinstance<py::bool_>(t[11]) ||
        !crc32(t[keys_at + 1], crc32(t[keys_at])).equal(t[11]))
      bad_state("the voxels do not match their CRC-32: the state is damaged");
  }
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    bad_state(e.what());
  }
  std::optional<Map> map;
  try {
    map.emplace(resolution, p);
  } catch (const std::invalid_argument& e) {
    bad_state(e.what());
  }
  std::size_t bad = n;
  {
    const py::gil_scoped_release nogil;
    for (std::size_t i = 0; i < n && bad == n; ++i) {
      std::uint16_t k[3];
      float v;
      std::memcpy(k, keys.data() + 3 * sizeof(std::uint16_t) * i, sizeof k);
      std::memcpy(&v, values.data() + sizeof(float) * i, sizeof v);
      if (!std::isfinite(v))
        bad = i;
      else
        map->set(OcKey(k[0], k[1], k[2]), v);
    }
    map->set_memory_limit(memory_limit);
  }
  if (bad < n) bad_state("voxel " + std::to_string(bad) + " has a log-odds that is not finite");
  if (map->num_voxels() != n)
    bad_state(std::to_string(n - map->num_voxels()) + " voxel keys appear twice");
  try {
    auto object = make_map_object(std::move(*map), prob_hit, prob_miss);
    return MapRef{object, object};
  } catch (const std::invalid_argument& e) {
    bad_state(e.what());
  }
}

std::string repr(const MapRef& self) {
  try {
    const auto lock = self.owner->guard.read("repr");
    const Map& map = self.owner->map();
    return "<knnocc.OccupancyMap resolution " + std::to_string(map.resolution()) + ", " +
           std::to_string(map.num_voxels()) + " known voxels" +
           (self.object ? "" : ", of a Mapper or LiveMapper") + ">";
  } catch (const std::runtime_error&) {
    return "<knnocc.OccupancyMap (another thread is changing it)>";
  }
}

constexpr const char* kClassDoc =
    R"(A sparse voxel occupancy map with OctoMap's semantics and files.

OccupancyMap(resolution, prob_hit=0.7, prob_miss=0.4, clamp_min=0.1192, clamp_max=0.971)

resolution: voxel edge in metres. prob_hit / prob_miss: OctoMap's sensor model for
insert_point_cloud (hit in (0.5, 1), miss in (0, 0.5)). clamp_min / clamp_max: OctoMap's
clamping thresholds as probabilities. Voxels hold log-odds; a voxel is occupied when its
log-odds is >= 0 (probability 0.5).

Points are (N, 3) arrays (any (..., 3) shape); C-contiguous float32 or float64 arrays are read in
place, anything else is converted once. Insertion works in float32, like OctoMap.

  m = knnocc.OccupancyMap(0.05)
  m.insert_point_cloud(points, origin=(0, 0, 1))        # world-frame points, sensor position
  occ = m.occupancy_at(queries)                         # int8: -1 unknown, 0 free, 1 occupied
  occupied, free = m.extract_point_cloud()              # voxel centres, float64
  m.write("map.bt")                                     # or .ot; knnocc.read_map reads both

The map of a Mapper or LiveMapper (their .map) is an OccupancyMap that reads only.
Thread safety: one writer (insert_point_cloud, memory_limit =) or any number of readers at once;
a call that would break this raises RuntimeError. The GIL is released while the library works.)";

}  // namespace

void bind_map(py::module_& m) {
  py::class_<MapRef> c(m, "OccupancyMap", kClassDoc);
  c.def(py::init([](double resolution, double prob_hit, double prob_miss, double clamp_min,
                    double clamp_max) {
          auto object = make_map_object(Map(resolution, occupancy_params(clamp_min, clamp_max)),
                                        prob_hit, prob_miss);
          return MapRef{object, object};
        }),
        py::arg("resolution"), py::arg("prob_hit") = 0.7, py::arg("prob_miss") = 0.4,
        py::arg("clamp_min") = 0.1192, py::arg("clamp_max") = 0.971,
        "A new empty map; ValueError for a resolution <= 0 (or below 1e-6 m) or probabilities "
        "out of range.");
  c.def(
      "insert_point_cloud",
      [](const MapRef& self, const py::object& points, const py::object& origin, double max_range,
         int threads, bool discretize) {
        MapObject& object = self.writable("OccupancyMap.insert_point_cloud");
        if (threads < 1 || threads > 1024)
          throw py::value_error("threads must be in [1, 1024], got " + std::to_string(threads));
        const PointsIn in(points, "points", limit_of(object, "OccupancyMap.insert_point_cloud"));
        const Point3d o = vec3_in(origin, "origin");
        const auto lock = object.guard.write("OccupancyMap.insert_point_cloud");
        const py::gil_scoped_release nogil;
        object.insert_point_cloud(o, in.view(), max_range, static_cast<unsigned>(threads),
                                  discretize);
      },
      py::arg("points"), py::arg("origin"), py::arg("max_range") = -1.0, py::arg("threads") = 1,
      py::arg("discretize") = false,
      R"(Inserts one scan, as OctoMap's insertPointCloud: `points` (N, 3) in the world frame, seen
from `origin` (3 numbers). A point within max_range of the origin marks its voxel occupied and
the voxels on its ray free; a farther one frees its ray up to max_range only (max_range < 0: no
limit; 0 or NaN: ValueError). Occupied wins over free within a scan, each voxel is updated once.
NaN/Inf points and points outside the key range are skipped. threads: threads that walk the rays
(the map is the same for every count). discretize: first reduce the points to their distinct
voxels (OctoMap's option). MemoryError when the map would pass its memory_limit.)");
  c.def("occupancy_at", &occupancy_at, py::arg("points"),
        "int8 array of shape points.shape[:-1]: -1 unknown (or outside the key range), 0 free, "
        "1 occupied, for the voxel holding each point.");
  c.def("logodds_at", &logodds_at, py::arg("points"),
        "float32 array of shape points.shape[:-1]: the log-odds of the voxel holding each point, "
        "NaN where unknown.");
  c.def("extract_point_cloud", &extract_point_cloud,
        "(occupied, free): the centres of the occupied and of the free known voxels, each an "
        "(M, 3) float64 array (OctoMap's extractPointCloud at the finest level), in storage "
        "order.");
  c.def("voxels", &voxels, py::arg("which") = "all",
        "(centres, logodds): the known voxels' centres, (M, 3) float64, and log-odds, (M,) "
        "float32; which: 'occupied', 'free' or 'all'.");
  c.def(
      "count_voxels",
      [](const MapRef& self) {
        const auto lock = self.owner->guard.read("OccupancyMap.count_voxels");
        const VoxelCounts n = self.owner->map().count_voxels();
        return py::make_tuple(n.occupied, n.free);
      },
      "(occupied, free): the numbers of known finest-level voxels of each kind.");
  c.def(
      "__len__",
      [](const MapRef& self) {
        const auto lock = self.owner->guard.read("OccupancyMap.__len__");
        return self.owner->map().num_voxels();
      },
      "The number of known (occupied or free) finest-level voxels.");
  c.def_property_readonly(
      "resolution",
      [](const MapRef& self) {
        const auto lock = self.owner->guard.read("OccupancyMap.resolution");
        return self.owner->map().resolution();
      },
      "Voxel edge in metres.");
  c.def_property(
      "memory_limit",
      [](const MapRef& self) {
        const auto lock = self.owner->guard.read("OccupancyMap.memory_limit");
        return self.owner->map().memory_limit();
      },
      [](const MapRef& self, const py::object& bytes) {
        const std::size_t limit = memory_limit_in(bytes);
        MapObject& object = self.writable("OccupancyMap.memory_limit");
        const auto lock = object.guard.write("OccupancyMap.memory_limit");
        object.set_memory_limit(limit);
      },
      "Bytes the map (and the inserter's scratch) may use; 0: no limit (the default). An "
      "insertion that would pass it raises MemoryError.");
  c.def("write", &write, py::arg("path"),
        "Writes the map as an OctoMap file chosen by the extension: .bt (binary tree: occupied or "
        "free, what octovis and octomap_server read) or .ot (full tree with log-odds); the bytes "
        "liboctomap writes for the same map. The file is written to a temporary name and "
        "renamed. knnocc.Error when it cannot be written.");
  c.def("to_bytes", &to_bytes, py::arg("format") = "bt",
        "The bytes write() would put in a .bt ('bt') or .ot ('ot') file.");
  c.def("cast_ray", &cast_ray, py::arg("origin"), py::arg("direction"), py::arg("max_range") = -1.0,
        py::arg("ignore_unknown") = false,
        R"((hit, end): OctoMap's castRay from `origin` along `direction` (3 numbers each): the walk
starts in the origin's voxel and stops at the first occupied voxel (hit True), at an unknown voxel
unless ignore_unknown, beyond max_range (<= 0: no limit) or at the edge of the key range (hit
False); end is the centre of the voxel where it stopped. With (N, 3) origins and/or directions:
hit is a bool array (N,) and end (N, 3). ValueError for a non-finite origin or one outside the
map, or a zero direction.)");
  c.def(
      "__eq__",
      [](const MapRef& a, const MapRef& b) {
        const auto lock_a = a.owner->guard.read("OccupancyMap.__eq__");
        const auto lock_b = b.owner->guard.read("OccupancyMap.__eq__");
        const py::gil_scoped_release nogil;
        return a.owner->map().resolution() == b.owner->map().resolution() &&
               same_voxels(a.owner->map(), b.owner->map());
      },
      py::arg("other"), py::is_operator(),
      "True when both maps have the same resolution and the same known voxels, each with the "
      "same log-odds bit for bit.");
  c.def("__repr__", &repr);
  c.def(py::pickle(&get_state, &set_state));
  refuse_uninitialised(c);

  m.def(
      "read_map",
      [](const py::object& path_obj) {
        const std::string path = path_in(path_obj);
        return wrap(make_map_object(without_gil([&] { return io::read_octree(path); }), 0.7, 0.4));
      },
      py::arg("path"),
      "Reads an OctoMap .bt or .ot file (told apart by its first line) into a new OccupancyMap "
      "(.bt leaves get the clamping bounds, .ot leaves keep their log-odds). knnocc.Error when "
      "the file is missing or malformed.");
  m.def("cast_ray", &cast_ray, py::arg("map"), py::arg("origin"), py::arg("direction"),
        py::arg("max_range") = -1.0, py::arg("ignore_unknown") = false,
        "map.cast_ray(origin, direction, ...), as C++'s cast_ray(map, ...).");
}

}  // namespace knnocc::python
