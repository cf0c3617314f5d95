// The knnocc Python module: exceptions, the conversions of binding.hpp, and the parts bound in
// map.cpp, mappers.cpp and io.cpp.

#include <cmath>
#include <string>

#include <knnocc/io/error.hpp>
#include <knnocc/version.hpp>

#include <pybind11/eval.h>

#include "binding.hpp"

namespace knnocc::python {

namespace {
constexpr int kAligned = 0x0100;  // NPY_ARRAY_ALIGNED: numpy's flag, not in pybind11's enum
template <class T>
using InPlace = py::array_t<T, py::array::c_style | py::array::forcecast | kAligned>;

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// numpy's own conversion (np.asarray) of obj to a C-contiguous, aligned array of T, a view when
// obj is one already; null when obj is not numbers. numpy's MemoryError (a copy of a huge strided
// or broadcast array) stays a MemoryError.
template <class T>
InPlace<T> in_place(py::handle obj) {
  const auto& api = py::detail::npy_api::get();
  PyObject* r = api.PyArray_FromAny_(obj.ptr(), py::dtype::of<T>().release().ptr(), 0, 0,
                                     py::detail::npy_api::NPY_ARRAY_ENSUREARRAY_ |
                                         py::array::c_style | py::array::forcecast | kAligned,
                                     nullptr);
  if (!r) {
    if (PyErr_ExceptionMatches(PyExc_MemoryError)) throw py::error_already_set();
    PyErr_Clear();
  }
  return py::reinterpret_steal<InPlace<T>>(r);
}

// A C-contiguous float64 array; ValueError if obj is not numbers.
py::array_t<double> doubles_in(py::handle obj, const char* name) {
  auto a = in_place<double>(obj);
  if (!a) throw py::value_error(std::string(name) + " must be an array of numbers");
  return std::move(a);
}

// Whether `a` (an object array) holds only Python integers: integers too large for numpy's types.
bool only_ints(const py::array& a) {
  for (const py::handle v : a.attr("flat"))
    if (!py::isinstance<py::int_>(v)) return false;
  return true;
}
}  // namespace

PointsIn::PointsIn(py::handle obj, const char* name, std::size_t copy_limit) {
  const bool f32 = py::isinstance<py::array>(obj) &&
                   py::reinterpret_borrow<py::array>(obj).dtype().equal(py::dtype::of<float>());
  if (copy_limit && py::isinstance<py::array>(obj)) {
    const auto a = py::reinterpret_borrow<py::array>(obj);
    const bool in_place = (f32 || a.dtype().equal(py::dtype::of<double>())) &&
                          (a.flags() & py::array::c_style) && (a.flags() & kAligned);
    const double bytes = double(a.size()) * (f32 ? 4.0 : 8.0);
    if (!in_place && bytes > double(copy_limit)) {
      PyErr_SetString(PyExc_MemoryError,
                      (std::string(name) + ": the " + shape_text(a) +
                       " array is not a C-contiguous float32 or float64 array; its copy would "
                       "need " +
                       std::to_string(bytes / 1e6) + " MB, more than the memory limit")
                          .c_str());
      throw py::error_already_set();
    }
  }
  if (f32)
    array_ = in_place<float>(obj);
  else
    array_ = in_place<double>(obj);
  if (!array_) throw py::value_error(std::string(name) + " must be an (N, 3) array of numbers");
  if (array_.ndim() < 1 || array_.shape(array_.ndim() - 1) != 3)
    throw py::value_error(std::string(name) + " must have shape (N, 3), got " + shape_text(array_));
  view_ = PointsView{array_.data(), static_cast<std::size_t>(array_.size() / 3), f32};
  last_points_input = {reinterpret_cast<std::uintptr_t>(array_.data()), array_.ptr() != obj.ptr()};
}

std::vector<py::ssize_t> PointsIn::outer_shape() const {
  return std::vector<py::ssize_t>(array_.shape(), array_.shape() + array_.ndim() - 1);
}

Point3d vec3_in(py::handle obj, const char* name) {
  const auto a = doubles_in(obj, name);
  if (a.size() != 3) throw py::value_error(std::string(name) + " must be 3 numbers");
  const double* v = a.data();
  if (!(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])))
    throw py::value_error(std::string(name) + " must be finite");
  return {v[0], v[1], v[2]};
}

Pose pose_in(py::handle obj, const char* name) {
  const auto a = doubles_in(obj, name);
  const std::string what(name);
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw py::value_error(what + " must be a 4x4 matrix, got shape " + shape_text(a));
  const double* m = a.data();  // row-major
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(m[i])) throw py::value_error(what + " must be finite");
  if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
    throw py::value_error(what + ": the last row of a rigid transform is 0 0 0 1");
  Pose p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.r(r, c) = m[4 * r + c];
    p.t(r) = m[4 * r + 3];
  }
  const double off = (p.r.transpose() * p.r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(off <= 1e-3) || !(p.r.determinant() > 0.0))
    throw py::value_error(what + ": the upper-left 3x3 block is not a rotation (within 1e-3)");
  return p;
}

std::vector<PointEvidence> evidence_in(py::handle obj, std::size_t n, const char* name) {
  if (obj.is_none()) return {};
  const std::string what(name);
  const auto kind = py::array::ensure(obj);
  if (kind && kind.dtype().kind() == 'O' && kind.size() > 0 && only_ints(kind))
    throw py::value_error(what + " must be in [0, 2^32 - 1]");
  if (!kind || (kind.dtype().kind() != 'i' && kind.dtype().kind() != 'u'))
    throw py::value_error(what +
                          " must be integers (found, visible, observations per point) or "
                          "None");
  const auto a = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(kind);
  if (!a || a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != n || a.shape(1) != 3)
    throw py::value_error(what + " must have shape (" + std::to_string(n) +
                          ", 3): found, visible, observations per point; got shape " +
                          shape_text(kind));
  std::vector<PointEvidence> out(n);
  const std::int64_t* v = a.data();
  for (std::size_t i = 0; i < n; ++i, v += 3) {
    for (int c = 0; c < 3; ++c)
      if (v[c] < 0 || v[c] > 0xFFFFFFFFll)
        throw py::value_error(what + " must be in [0, 2^32 - 1]");
    out[i] = PointEvidence{static_cast<std::uint32_t>(v[0]), static_cast<std::uint32_t>(v[1]),
                           static_cast<std::uint32_t>(v[2])};
  }
  return out;
}

std::vector<std::uint64_t> ids_in(py::handle obj, std::size_t n, const char* name) {
  if (obj.is_none()) return {};
  const std::string what(name);
  const auto kind = py::array::ensure(obj);  // plain conversion, to look at the dtype
  if (kind && kind.dtype().kind() == 'O' && kind.size() > 0 && only_ints(kind))
    throw py::value_error(what + " must be map-point ids in [0, 2^64 - 1]");
  if (!kind || (kind.dtype().kind() != 'i' && kind.dtype().kind() != 'u'))
    throw py::value_error(what + " must be integers (one map-point id per point) or None");
  std::vector<std::uint64_t> ids;
  auto check_length = [&](const py::array& a) {
    if (a.ndim() != 1 || static_cast<std::size_t>(a.size()) != n)
      throw py::value_error(what + " must hold one id per point: " + std::to_string(n) +
                            " expected, got shape " + shape_text(a));
  };
  if (kind.dtype().kind() == 'u') {
    const auto a = in_place<std::uint64_t>(kind);
    check_length(a);
    ids.assign(a.data(), a.data() + a.size());
  } else {
    const auto a = in_place<std::int64_t>(kind);
    check_length(a);
    ids.reserve(n);
    for (py::ssize_t i = 0; i < a.size(); ++i) {
      if (a.data()[i] < 0) throw py::value_error(what + " must not be negative");
      ids.push_back(static_cast<std::uint64_t>(a.data()[i]));
    }
  }
  return ids;
}

U64 u64_of(py::handle obj, bool bools) {
  U64 r;
  if (!py::isinstance<py::int_>(obj) || (!bools && py::isinstance<py::bool_>(obj))) return r;
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(obj.ptr(), &overflow);
  if (overflow < 0 || (overflow == 0 && v < 0)) {
    r.kind = U64::negative;
  } else if (overflow == 0) {
    r.kind = U64::ok;
    r.value = static_cast<std::uint64_t>(v);
  } else {  // beyond long long: uint64 still holds up to 2^64 - 1
    r.value = PyLong_AsUnsignedLongLong(obj.ptr());
    r.kind = PyErr_Occurred() ? U64::too_large : U64::ok;
    PyErr_Clear();
  }
  return r;
}

std::uint64_t id_in(py::handle obj, const char* name) {
  const U64 v = u64_of(obj, true);
  if (v.kind == U64::not_integer) throw py::type_error(std::string(name) + " must be an integer");
  if (v.kind == U64::negative) throw py::value_error(std::string(name) + " must not be negative");
  if (v.kind == U64::too_large) throw py::value_error(std::string(name) + " must be below 2**64");
  return v.value;
}

std::size_t memory_limit_in(py::handle obj) {
  const U64 v = u64_of(obj, false);
  if (v.kind == U64::not_integer)
    throw py::type_error("memory_limit must be an integer (bytes; 0: no limit)");
  if (v.kind == U64::negative)
    throw py::value_error("memory_limit must not be negative (bytes; 0: no limit)");
  if (v.kind == U64::too_large) throw py::value_error("memory_limit must be below 2**64 bytes");
  return v.value;
}

std::string path_in(py::handle obj) {
  return py::module_::import("os").attr("fsdecode")(obj).cast<std::string>();
}

py::array_t<double> pose_out(const Pose& p) {
  py::array_t<double> a({4, 4});
  double* m = a.mutable_data();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[4 * r + c] = p.r(r, c);
    m[4 * r + 3] = p.t(r);
  }
  m[12] = m[13] = m[14] = 0.0;
  m[15] = 1.0;
  return a;
}

MapObject& MapRef::writable(const char* what) const {
  if (!object)
    throw py::value_error(std::string(what) +
                          ": this map belongs to a Mapper or LiveMapper and is read-only "
                          "(insert through its owner)");
  return *object;
}

}  // namespace knnocc::python

// The compiled part of the package knnocc (examples/python/knnocc/__init__.py imports it).
// Its classes and functions say they belong to `knnocc`, where users (and pickles) find them.
PYBIND11_MODULE(_knnocc, m) {
  namespace py = pybind11;
  using namespace knnocc::python;
  const py::object own_name = m.attr("__name__");
  m.attr("__name__") = "knnocc";
  m.doc() = R"(knnocc: 3D occupancy mapping (OctoMap's model bit for bit, the k-NN model, the robust
model), numpy in and numpy out, on the header-only C++ library.

  import knnocc, numpy as np
  m = knnocc.OccupancyMap(0.1)
  m.insert_point_cloud(np.random.rand(1000, 3).astype(np.float32), origin=(0, 0, 0))
  m.occupancy_at([[0.5, 0.5, 0.5]])      # -1 unknown, 0 free, 1 occupied
  m.write("map.bt")                      # octovis opens it

Classes: OccupancyMap, Mapper (one keyframe at a time, any model), LiveMapper (keyframes added,
re-posed, removed under SLAM corrections), Sequence (read_sequence). Functions: read_points,
read_sequence, read_trajectory, read_map, to_world, cast_ray.
Threads: the GIL is released during insertion, queries, ray casts and file I/O, so threads work
on different objects at once. One object takes one writer, or readers while no writer runs; a
call that would break this raises RuntimeError. Errors: bad arguments ValueError (wrong types
TypeError), unreadable or malformed files knnocc.Error (an OSError naming the file), the memory
limit MemoryError.)";
  m.attr("__version__") = KNNOCC_VERSION_STRING;

  // knnocc.Error: an OSError whose str() is the library's one line, "FILE: problem" (OSError's
  // own str() would show "[Errno None] None: 'FILE'" once filename is set). Kept for the life of
  // the process: the translator raises it at any time.
  py::dict scope;
  scope["__name__"] = "knnocc";
  // A failed system call's errno also picks the matching OSError subclass (knnocc.Error.
  // FileNotFoundError is a knnocc.Error and a FileNotFoundError), so `except FileNotFoundError`
  // works as with open().
  py::exec(R"(class Error(OSError):
    """An unreadable or malformed input file, or an output that cannot be written.

    str(e) is "FILE: problem"; e.filename is the file, e.strerror the problem and e.errno the
    errno of the system call that failed (None for a problem in the file's content). With an
    errno it is also the matching OSError subclass: a missing file is an
    Error.FileNotFoundError, which `except FileNotFoundError` catches."""

    def __str__(self):
        if self.filename is not None and self.strerror is not None:
            return f"{self.filename}: {self.strerror}"
        return super().__str__()


for _base in (FileNotFoundError, FileExistsError, PermissionError, IsADirectoryError,
              NotADirectoryError, InterruptedError, TimeoutError):
    _sub = type(_base.__name__, (Error, _base), {"__module__": "knnocc",
                "__doc__": f"A knnocc.Error that is also a {_base.__name__}."})
    _sub.__qualname__ = "Error." + _base.__name__
    setattr(Error, _base.__name__, _sub)


def _error(errno, problem, file):
    cls = Error
    if errno:
        cls = getattr(Error, type(OSError(errno, "")).__name__, Error)
    return cls(errno or None, problem, file)
)",
           scope);
  static PyObject* error = py::object(scope["Error"]).release().ptr();
  static PyObject* make_error = py::object(scope["_error"]).release().ptr();
  m.add_object("Error", py::handle(error).inc_ref());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const knnocc::io::Error& e) {
      const py::object exc = py::handle(make_error)(e.sys_errno(), e.problem(), e.file());
      PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exc.ptr())), exc.ptr());
    }
  });

  bind_map(m);
  bind_mappers(m);
  bind_io(m);
  bind_knn2022(m);
  bind_tiles(m);

  m.def(
      "_last_points_input",
      [] { return py::make_tuple(last_points_input.address, last_points_input.converted); },
      "For tests: (address, converted) of the last point array this thread passed in: the "
      "address of the buffer the library read, and whether the input had to be converted.");
  m.attr("__name__") = own_name;
}
