#pragma once
// What the module's pybind11 translation units share: numpy in (points read in place, origins,
// poses, ids, paths) and out (arrays that adopt a std::vector), and Python's OccupancyMap
// (MapRef), which Mapper.map and LiveMapper.map also return.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "owners.hpp"
#include "uninitialised.hpp"

namespace knnocc::python {

namespace py = pybind11;

void bind_map(py::module_& m);
void bind_mappers(py::module_& m);
void bind_io(py::module_& m);
void bind_knn2022(py::module_& m);
void bind_tiles(py::module_& m);

/// The buffer the last PointsIn of this thread read and whether it had to be converted: what
/// knnocc._last_points_input() tells the tests that prove inputs are read in place.
struct InputRecord {
  std::uintptr_t address = 0;
  bool converted = false;
};
inline thread_local InputRecord last_points_input;

/// An (N, 3) (or (..., 3)) array of points. A C-contiguous, aligned float32 or float64 numpy
/// array is read in place; anything else is converted once (float32 arrays to float32, the rest
/// to float64). ValueError for a shape without a last axis of 3 or values that are not numbers.
/// `copy_limit` (bytes, 0: none): an array whose copy would need more is refused with MemoryError
/// before numpy allocates it (an object's memory_limit covers the copy of its input).
class PointsIn {
 public:
  PointsIn(py::handle obj, const char* name, std::size_t copy_limit = 0);
  const PointsView& view() const { return view_; }
  std::size_t size() const { return view_.size; }
  /// The input's shape without its last axis: the shape of one result per point.
  std::vector<py::ssize_t> outer_shape() const;

 private:
  py::array array_;  // keeps the buffer alive while the library reads it
  PointsView view_;
};

/// Three finite numbers (a sensor origin, a ray direction); ValueError otherwise.
Point3d vec3_in(py::handle obj, const char* name);
/// A 4x4 sensor-to-world rigid transform (last row 0 0 0 1, rotation within 1e-3); ValueError
/// otherwise.
Pose pose_in(py::handle obj, const char* name);
/// None (no ids) or n non-negative integers; ValueError otherwise.
std::vector<std::uint64_t> ids_in(py::handle obj, std::size_t n, const char* name);
/// None (no counters) or an (n, 3) integer array of a SLAM system's found, visible and
/// observations counts per point (core/point_evidence.hpp), each in [0, 2^32 - 1]; ValueError
/// otherwise.
std::vector<PointEvidence> evidence_in(py::handle obj, std::size_t n, const char* name);
/// What a Python object is as an unsigned 64-bit integer: the one test behind ids, memory limits
/// and pickled counts, each of which words its own error. `bools` says whether True/False count.
struct U64 {
  enum Kind { ok, not_integer, negative, too_large } kind = not_integer;
  std::uint64_t value = 0;
};
U64 u64_of(py::handle obj, bool bools);
/// A non-negative integer (a keyframe id); TypeError or ValueError otherwise.
std::uint64_t id_in(py::handle obj, const char* name);
/// A memory limit in bytes (0: no limit): TypeError for a non-integer, ValueError for a negative
/// one or one of 2**64 or more.
std::size_t memory_limit_in(py::handle obj);
/// The memory limit of `owner`, read under its guard (the input is converted before the call takes
/// the object, so readers are not refused during a copy).
inline std::size_t limit_of(MapOwner& owner, const char* what) {
  const auto lock = owner.guard.read(what);
  return owner.memory_limit();
}
/// A str, bytes or os.PathLike path.
std::string path_in(py::handle obj);
/// A pose as a 4x4 float64 array.
py::array_t<double> pose_out(const Pose& p);

/// f() with the GIL released; its result (a C++ value) is made before the GIL is taken back.
template <class F>
auto without_gil(F&& f) {
  const py::gil_scoped_release nogil;
  return f();
}

/// `v`'s elements as a numpy array of `shape` without a copy (the array owns the vector).
template <class Scalar, class Elem>
py::array_t<Scalar> adopt(std::vector<Elem>&& v, std::vector<py::ssize_t> shape) {
  static_assert(sizeof(Elem) % sizeof(Scalar) == 0, "whole scalars per element");
  if (v.empty()) return py::array_t<Scalar>(shape);
  auto* owned = new std::vector<Elem>(std::move(v));
  const py::capsule base(owned, [](void* p) { delete static_cast<std::vector<Elem>*>(p); });
  return py::array_t<Scalar>(shape, reinterpret_cast<const Scalar*>(owned->data()), base);
}

/// Python's OccupancyMap: a map of its own, or the map of a Mapper or LiveMapper (then it reads
/// only, and shares its owner's guard).
struct MapRef {
  std::shared_ptr<MapOwner> owner;
  std::shared_ptr<MapObject> object;  ///< null: the map of a Mapper or LiveMapper

  /// The map of its own; ValueError for a Mapper's or LiveMapper's map.
  MapObject& writable(const char* what) const;
};

}  // namespace knnocc::python
