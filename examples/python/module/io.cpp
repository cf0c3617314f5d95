// Files in, numpy out: read_points, read_sequence (a Sequence of keyframes), read_trajectory, and
// to_world, which moves sensor-frame points as the tool does.

#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/point_file.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/trajectory.hpp>

#include "binding.hpp"

namespace knnocc::python {

namespace {

// (points float32 (N, 3), ids uint64 (N,) or None), adopting the cloud's vectors.
py::tuple cloud_out(io::Cloud&& cloud) {
  const auto n = static_cast<py::ssize_t>(cloud.points.size());
  py::object ids = py::none();
  // Ids belong to the format: a cloud of zero points that declares them has an empty id array.
  if (cloud.has_ids()) ids = adopt<std::uint64_t>(std::move(cloud.ids), {n});
  return py::make_tuple(adopt<float>(std::move(cloud.points), {n, 3}), ids);
}

struct SequenceRef {
  std::string path;
  io::ScanSource source;
};

py::tuple keyframe(const SequenceRef& s, py::ssize_t i) {
  const auto n = static_cast<py::ssize_t>(s.source.size());
  if (i < 0) i += n;
  if (i < 0 || i >= n) throw py::index_error("keyframe index out of range");
  io::Scan scan = without_gil([&] { return s.source.load(static_cast<std::size_t>(i)); });
  py::tuple cloud = cloud_out(std::move(scan.cloud));
  return py::make_tuple(pose_out(Pose::from(scan.pose)), cloud[0], cloud[1]);
}

// The SLAM counters of keyframe i as (N, 3) uint32 (found, visible, observations), or None.
py::object keyframe_evidence(const SequenceRef& s, py::ssize_t i) {
  const auto n = static_cast<py::ssize_t>(s.source.size());
  if (i < 0) i += n;
  if (i < 0 || i >= n) throw py::index_error("keyframe index out of range");
  io::Scan scan = without_gil([&] { return s.source.load(static_cast<std::size_t>(i)); });
  if (scan.cloud.evidence.empty()) return py::none();
  const auto rows = static_cast<py::ssize_t>(scan.cloud.evidence.size());
  return adopt<std::uint32_t>(std::move(scan.cloud.evidence), {rows, 3});
}

constexpr const char* kSequenceDoc = R"(The keyframes of a sequence, loaded one at a time.

What read_sequence(path) returns: len(seq) keyframes; seq[i] (and iteration) gives
(pose, points, ids): pose a 4x4 float64 sensor-to-world matrix, points (N, 3) float32 in the
sensor frame, ids uint64 (N,) map-point ids or None. The same inputs as `knnocc map --input`:
a sequence folder (poses.txt and clouds/ or a KITTI velodyne/ with calib.txt), an OctoMap .graph
file, or one point file (sensor at the origin, or at a PCD file's VIEWPOINT).)";

}  // namespace

void bind_io(py::module_& m) {
  m.def(
      "read_points",
      [](const py::object& path_obj) {
        const std::string path = path_in(path_obj);
        return cloud_out(without_gil([&] { return io::read_points(path); }));
      },
      py::arg("path"),
      R"((points, ids): a point file as (N, 3) float32 and uint64 (N,) map-point ids (a PLY `id`
property) or None. Every cloud format the tool reads, by extension: .ply, .pcd (ascii, binary,
binary_compressed), KITTI .bin, ASCII .xyz/.dat/.txt. knnocc.Error when the file is missing or
malformed.)");

  py::class_<SequenceRef> seq(m, "Sequence", kSequenceDoc);
  seq.def(
      "__len__", [](const SequenceRef& s) { return s.source.size(); }, "The number of keyframes.");
  seq.def("__getitem__", &keyframe, py::arg("index"),
          "(pose, points, ids) of keyframe `index` (negative counts from the end); "
          "knnocc.Error when its file is malformed.");
  seq.def("evidence", &keyframe_evidence, py::arg("index"),
          "The SLAM counters of keyframe `index` (PLY `found`, `visible`, `observations`) as "
          "(N, 3) uint32, one row per point of seq[index], or None when its cloud has none; for "
          "Mapper.insert_keyframe(..., evidence=...).");
  seq.def(
      "__iter__",
      [](py::object self) {
        const auto n = static_cast<py::ssize_t>(self.cast<const SequenceRef&>().source.size());
        const auto builtins = py::module_::import("builtins");
        return builtins.attr("map")(self.attr("__getitem__"), builtins.attr("range")(n));
      },
      "The keyframes in order, each loaded when it is reached.");
  seq.def_property_readonly(
      "path", [](const SequenceRef& s) { return s.path; }, "The path it was opened with.");
  seq.def_property_readonly(
      "kind", [](const SequenceRef& s) { return std::string(s.source.kind()); },
      "'sequence folder', 'scan graph' or 'point file'.");
  seq.def("__repr__", [](const SequenceRef& s) {
    return "<knnocc.Sequence " + s.path + ": " + std::to_string(s.source.size()) + " keyframes>";
  });
  refuse_uninitialised(seq);

  m.def(
      "read_sequence",
      [](const py::object& path_obj) {
        std::string path = path_in(path_obj);
        io::ScanSource source = without_gil([&] { return io::ScanSource::open(path); });
        return SequenceRef{std::move(path), std::move(source)};
      },
      py::arg("path"),
      "The keyframes of a sequence folder (poses.txt + clouds/), an OctoMap .graph file or one "
      "point file, as a Sequence of (pose, points, ids). Poses are read now, clouds when they "
      "are reached. knnocc.Error when the folder or a file is missing or malformed.");

  m.def(
      "read_trajectory",
      [](const py::object& path_obj) {
        const std::string path = path_in(path_obj);
        const std::vector<io::Pose> poses = without_gil([&] { return io::read_trajectory(path); });
        py::array_t<double> out(
            {static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
        for (std::size_t i = 0; i < poses.size(); ++i) {
          const auto one = pose_out(Pose::from(poses[i]));
          std::copy(one.data(), one.data() + 16, out.mutable_data() + 16 * i);
        }
        return out;
      },
      py::arg("path"),
      "A trajectory file (TUM lines 'stamp tx ty tz qx qy qz qw' or KITTI 3x4 lines, as "
      "poses.txt) as (N, 4, 4) float64 sensor-to-world matrices, exactly the poses "
      "read_sequence gives. knnocc.Error when malformed.");

  m.def(
      "to_world",
      [](const py::object& pose, const py::object& points) {
        const Pose p = pose_in(pose, "pose");
        const PointsIn in(points, "points");
        std::vector<py::ssize_t> shape = in.outer_shape();
        shape.push_back(3);
        py::array_t<double> out(shape);
        double* o = out.mutable_data();
        {
          const py::gil_scoped_release nogil;
          in.view().visit([&](const auto& span) {
            for (std::size_t i = 0; i < span.size(); ++i) {
              const Eigen::Vector3d w = p.apply(span[i].x, span[i].y, span[i].z);
              o[3 * i] = w.x();
              o[3 * i + 1] = w.y();
              o[3 * i + 2] = w.z();
            }
          });
        }
        return out;
      },
      py::arg("pose"), py::arg("points"),
      "R @ p + t for every point (pose a 4x4 sensor-to-world matrix, points (N, 3)) as (N, 3) "
      "float64, computed as the knnocc tool and LiveMapper compute it, so that Mapper gets the "
      "tool's points bit for bit (numpy's matmul may round differently).");
}

}  // namespace knnocc::python
