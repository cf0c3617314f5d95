// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The tracker concept: what Mapper (mapper.hpp) asks of the tracker that keeps the map point
// cloud's k-NN statistics for a rated sensor model (sensor/sensor_model.hpp):
//   TrackerUpdate apply(const ChangeSet& change);     one change of the map point cloud (Alg. 2)
//   bool contains(std::uint64_t id) const;           the map point is in the cloud
//   double s(std::uint64_t id) const;                its mean k-NN distance (NaN: none yet)
//   const RunningNormal& distribution() const;       N(mu, sigma) of the valid s (eq 6-12)
// KnnTracker (knn/tracker.hpp) is the library's, with the affected-points rule as its policy;
// examples/custom_policies.cpp writes a tracker of its own.

#include <cstdint>
#include <type_traits>
#include <utility>

#include "../stats/welford.hpp"
#include "change_set.hpp"
#include "tracker_types.hpp"

namespace knnocc::detail {

template <class T, class = void>
struct has_tracker_apply : std::false_type {};
template <class T>
struct has_tracker_apply<
    T, std::enable_if_t<std::is_convertible_v<
           decltype(std::declval<T&>().apply(std::declval<const ChangeSet&>())), TrackerUpdate>>>
    : std::true_type {};

template <class T, class = void>
struct has_tracker_queries : std::false_type {};
template <class T>
struct has_tracker_queries<
    T, std::void_t<decltype(static_cast<bool>(std::declval<const T&>().contains(std::uint64_t{}))),
                   decltype(static_cast<double>(std::declval<const T&>().s(std::uint64_t{}))),
                   decltype(static_cast<const RunningNormal&>(
                       std::declval<const T&>().distribution()))>> : std::true_type {};

/// Compiles only for a type that meets the tracker concept; the message names what is missing.
template <class T>
constexpr bool check_tracker() {
  static_assert(
      has_tracker_apply<T>::value,
      "a tracker needs `TrackerUpdate apply(const ChangeSet&)` (knn/tracker_concept.hpp)");
  static_assert(has_tracker_queries<T>::value,
                "a tracker needs `bool contains(std::uint64_t) const`, `double s(std::uint64_t) "
                "const` and `const RunningNormal& distribution() const` (knn/tracker_concept.hpp)");
  return true;
}

}  // namespace knnocc::detail
