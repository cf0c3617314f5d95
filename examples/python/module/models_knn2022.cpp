// The authors' 2022 model (Miao et al., Sensors 22(1):139): Mapper only, as the tool (the live
// mapper does not take it), and its first pass over a sequence for mu and sigma.

#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/sensor/knn2022_model.hpp>

#include "binding.hpp"
#include "model_owners.hpp"
#include "points.hpp"

namespace knnocc::python {

std::shared_ptr<MapperOwner> make_knn2022_mapper(double resolution, const ModelOptions& o,
                                                 bool wide) {
  return make_mapper_of(resolution, Knn2022Model(o.knn2022), o.mapper, wide, "knn2022");
}

Knn2022Params knn2022_first_pass(const io::ScanSource& source, const Knn2022Params& p, double crop,
                                 bool world_points, std::size_t first, std::size_t last) {
  Knn2022FirstPass pass(p);
  std::vector<Point3f> f;
  std::vector<Point3d> d;
  for (std::size_t i = first; i < last; ++i) {
    io::Scan scan = source.load(i);
    if (world_points) io::transform_to_sensor(scan.pose, scan.cloud.points);
    io::crop_cloud(scan.cloud, crop);
    if (io::is_identity(scan.pose))
      f.swap(scan.cloud.points);
    else
      io::transform_to_world(scan.pose, scan.cloud.points, f);
    d.clear();
    for (const Point3f& q : f) d.push_back(Point3d{q.x, q.y, q.z});
    pass.add(Point3d{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()}, d);
  }
  return pass.params();
}

namespace {

// Knn2022FirstPass over the clouds given, each rounded to float world points as the tool gives
// them to the model.
struct FirstPass {
  Knn2022FirstPass pass;
  std::vector<Point3d> points;
};

constexpr const char* kFirstPassDoc =
    R"(The 2022 model's first pass (the authors' statistics): mu and sigma of d, each inner point's
mean distance to its k nearest inner points of its own cloud, over every cloud added.

Knn2022FirstPass(k=24, inner_range=4.0)

  stats = knnocc.Knn2022FirstPass()
  for pose, points, ids in knnocc.read_sequence("keyframes"):
      stats.add(pose[:3, 3], knnocc.to_world(pose, points))
  mapper = knnocc.Mapper(0.1, model="knn2022", mu=stats.mu, sigma=stats.sigma)

The same clouds then give the map of `knnocc map --model knn2022` (its default --stats
first-pass), byte for byte. Points are rounded to float32 first, as the tool rounds them.)";

}  // namespace

void bind_knn2022(py::module_& m) {
  py::class_<FirstPass> c(m, "Knn2022FirstPass", kFirstPassDoc);
  c.def(py::init([](long long k, double inner_range) {
          if (k < 1 || k > 4096) throw py::value_error("k must be in [1, 4096]");
          Knn2022Params p;
          p.k = static_cast<std::size_t>(k);
          p.inner_range = inner_range;
          return FirstPass{Knn2022FirstPass(p), {}};  // validates (ValueError)
        }),
        py::arg("k") = static_cast<long long>(Knn2022Params{}.k),
        py::arg("inner_range") = Knn2022Params{}.inner_range,
        "A first pass with the 2022 model's k and inner range.");
  c.def(
      "add",
      [](FirstPass& self, const py::object& origin, const py::object& points) {
        const Point3d o = vec3_in(origin, "origin");
        const PointsIn in(points, "points");
        self.points.clear();
        in.view().visit([&](const auto& span) {
          for (std::size_t i = 0; i < span.size(); ++i) {
            const Point3f f = knnocc::detail::to_point3f(span[i]);
            self.points.push_back(Point3d{f.x, f.y, f.z});
          }
        });
        const py::gil_scoped_release nogil;
        self.pass.add(o, self.points);
      },
      py::arg("origin"), py::arg("points"),
      "One cloud: `points` (N, 3) in the world frame seen from `origin` (3 numbers).");
  c.def_property_readonly(
      "mu", [](const FirstPass& self) { return self.pass.params().mu; },
      "The mean of d over the clouds added (0 before any inner point).");
  c.def_property_readonly(
      "sigma", [](const FirstPass& self) { return self.pass.params().sigma; },
      "The standard deviation of d over the clouds added.");
  c.def_property_readonly(
      "count", [](const FirstPass& self) { return self.pass.distribution().count(); },
      "Inner points with a finite d so far.");
  refuse_uninitialised(c);
}

}  // namespace knnocc::python
