// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One trait gives knnocc the coordinates of any point type.
//
// Supported out of the box:
//   - any type with public members x, y, z (PCL points, ROS messages, knnocc::Point3f, ...)
//   - Eigen fixed-size 3-vectors (Eigen::Vector3f, Eigen::Vector3d, ...)
//   - std::array<T, 3> with T arithmetic
// Anything else: specialise knnocc::point_traits<YourPoint> with
//   using scalar = float|double;  static scalar x(const P&), y(const P&), z(const P&);

#include <array>
#include <limits>
#include <type_traits>
#include <utility>

#include "point3.hpp"

namespace knnocc {

template <class P, class Enable = void>
struct point_traits {
  // Primary template: not a point. detail::point_access reports this with a static_assert.
  static constexpr bool is_specialised = false;
};

namespace detail {

template <class P, class = void>
struct has_xyz_members : std::false_type {};
template <class P>
struct has_xyz_members<
    P, std::void_t<decltype(std::declval<const P&>().x), decltype(std::declval<const P&>().y),
                   decltype(std::declval<const P&>().z)>>
    : std::bool_constant<std::is_arithmetic_v<std::decay_t<decltype(std::declval<const P&>().x)>>> {
};

// Eigen fixed-size vectors expose RowsAtCompileTime/ColsAtCompileTime and operator()(i).
template <class P, class = void>
struct is_eigen_vec3 : std::false_type {};
template <class P>
struct is_eigen_vec3<P, std::void_t<decltype(P::RowsAtCompileTime), decltype(P::ColsAtCompileTime),
                                    typename P::Scalar>>
    : std::bool_constant<(P::RowsAtCompileTime == 3 && P::ColsAtCompileTime == 1) ||
                         (P::RowsAtCompileTime == 1 && P::ColsAtCompileTime == 3)> {};

template <class P>
struct is_std_array3 : std::false_type {};
template <class T>
struct is_std_array3<std::array<T, 3>> : std::is_arithmetic<T> {};

template <class P, class = void>
struct has_user_traits : std::true_type {};
template <class P>
struct has_user_traits<P, std::enable_if_t<!point_traits<P>::is_specialised>> : std::false_type {};

template <class P>
struct point_access {
  static constexpr bool user = has_user_traits<P>::value;
  static constexpr bool members = has_xyz_members<P>::value;
  static constexpr bool eigen = is_eigen_vec3<P>::value;
  static constexpr bool array = is_std_array3<P>::value;
  static_assert(user || members || eigen || array,
                "knnocc: this type is not a point. Give it public arithmetic members x, y, z, "
                "use an Eigen 3-vector or std::array<T,3>, or specialise knnocc::point_traits<P> "
                "(see knnocc/core/point_traits.hpp).");

  static auto x(const P& p) {
    if constexpr (user)
      return point_traits<P>::x(p);
    else if constexpr (members)
      return p.x;
    else if constexpr (eigen)
      return p(0);
    else
      return p[0];
  }
  static auto y(const P& p) {
    if constexpr (user)
      return point_traits<P>::y(p);
    else if constexpr (members)
      return p.y;
    else if constexpr (eigen)
      return p(1);
    else
      return p[1];
  }
  static auto z(const P& p) {
    if constexpr (user)
      return point_traits<P>::z(p);
    else if constexpr (members)
      return p.z;
    else if constexpr (eigen)
      return p(2);
    else
      return p[2];
  }
};

}  // namespace detail

/// True when P can be used as a point (members, Eigen, std::array or a point_traits
/// specialisation).
template <class P>
inline constexpr bool is_point_v =
    detail::has_user_traits<P>::value || detail::has_xyz_members<P>::value ||
    detail::is_eigen_vec3<P>::value || detail::is_std_array3<P>::value;

/// Coordinates of any supported point, in the point's own scalar type.
template <class P>
auto point_x(const P& p) {
  return detail::point_access<P>::x(p);
}
template <class P>
auto point_y(const P& p) {
  return detail::point_access<P>::y(p);
}
template <class P>
auto point_z(const P& p) {
  return detail::point_access<P>::z(p);
}

/// The scalar type of a point's coordinates (float for Eigen::Vector3f, double for Vector3d, ...).
template <class P>
using point_scalar_t = std::decay_t<decltype(point_x(std::declval<const P&>()))>;

namespace detail {

/// A coordinate as float: floats as they are; wider values rounded, and beyond float's range
/// +-inf instead of the undefined behaviour of a plain cast (NaN stays NaN).
template <class T>
inline float to_float(T v) noexcept {
  if constexpr (std::is_same_v<T, float> || !std::is_floating_point_v<T>) {
    return static_cast<float>(v);
  } else {
    constexpr T max = static_cast<T>(std::numeric_limits<float>::max());
    if (v > max) return std::numeric_limits<float>::infinity();
    if (v < -max) return -std::numeric_limits<float>::infinity();
    return static_cast<float>(v);
  }
}

/// Any point type as a Point3f (to_float per coordinate).
template <class P>
inline Point3f to_point3f(const P& p) noexcept {
  return Point3f{to_float(point_x(p)), to_float(point_y(p)), to_float(point_z(p))};
}

}  // namespace detail

}  // namespace knnocc
