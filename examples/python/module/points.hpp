#pragma once
// Points as the module hands them to the library: a span over an (N, 3) float32 or float64
// buffer (a numpy array's own memory, read in place), seen as Point3f or Point3d. A span of
// Point3f has the library's contiguous-float iterator (const Point3f*), so insertion takes the
// same vectorised path as for a std::vector<Point3f>.

#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include <knnocc/core/point3.hpp>

namespace knnocc::python {

static_assert(sizeof(Point3f) == 3 * sizeof(float) && std::is_standard_layout_v<Point3f>,
              "a float32 (N, 3) buffer is read as Point3f");
static_assert(sizeof(Point3d) == 3 * sizeof(double) && std::is_standard_layout_v<Point3d>,
              "a float64 (N, 3) buffer is read as Point3d");

/// Point3f or Point3d as float, rounded as the library rounds coordinates: beyond float's range
/// +-inf (a plain cast would be undefined), NaN stays NaN.
template <class P>
Point3f as_float(const P& p) {
  auto f = [](double v) {
    constexpr double max = std::numeric_limits<float>::max();
    if (v > max) return std::numeric_limits<float>::infinity();
    if (v < -max) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(v);
  };
  return {f(p.x), f(p.y), f(p.z)};
}

template <class P>
struct PointSpan {
  const P* first = nullptr;
  std::size_t n = 0;
  const P* begin() const { return first; }
  const P* end() const { return first + n; }
  std::size_t size() const { return n; }
  const P& operator[](std::size_t i) const { return first[i]; }
};

/// N points of 3 floats or 3 doubles, owned elsewhere.
struct PointsView {
  const void* data = nullptr;
  std::size_t size = 0;
  bool is_float = true;

  /// f(PointSpan<Point3f>) or f(PointSpan<Point3d>); both must return the same type.
  template <class F>
  decltype(auto) visit(F&& f) const {
    if (is_float) return f(PointSpan<Point3f>{static_cast<const Point3f*>(data), size});
    return f(PointSpan<Point3d>{static_cast<const Point3d*>(data), size});
  }
};

}  // namespace knnocc::python
