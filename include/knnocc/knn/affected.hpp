// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Affected-point policies: which existing map points need their k-NN recomputed after a change
// (paper section 3.2, "affected points"). A policy's collect(tracker, marks) reads the change and
// the cloud through the tracker's const queries (KnnTracker, section "policy interface") and names
// the affected points through `marks` (KnnTracker::Marks: mark(q), offer(q, p)), which only the
// tracker's apply() can make.
//
// ExactReverseKnn (default) is exact, with neighbours ordered by (distance, id):
//   - inserting p changes q's k-NN iff (d(q,p), id_p) < (d_k(q), id_k(q)), or q has fewer than k
//     neighbours, i.e. iff p falls in q's k-NN ball; the candidates are the balls registered
//     where p falls (knn/ball_grid.hpp). Such a q is offered p: its new k-NN are the best k of
//     its old ones and its offers, no query needed;
//   - removing p changes q's k-NN iff p is one of q's k neighbours: q is in p's reverse list.
// PaperAnnulus is the paper's Alg. 1 as written: grow a ball around each new/disappeared point by
// dr, recompute the points of each new annulus, stop when none of them changed or r >= s_max.
// It misses affected points beyond the first unchanged annulus; it is here to be compared.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "../core/config.hpp"
#include "point_index.hpp"

namespace knnocc {

struct ExactReverseKnn {
  void validate() const {}

  template <class Tracker, class Marks>
  void collect(const Tracker& t, Marks& marks) const {
    for (const std::uint32_t r : t.removed_indices())
      for (const std::uint32_t q : t.reverse_neighbours(r))
        if (t.alive(q) && !t.is_new(q)) marks.mark(q);

    if (t.size() == t.new_indices().size()) return;  // no old point left to affect
    std::vector<std::uint32_t> candidates;
    for (const std::uint32_t p : t.new_indices()) {
      const Point3d& pp = t.position_at(p);
      const std::uint64_t pid = t.id_at(p);
      auto test = [&](std::uint32_t q) {
        if (t.is_new(q) || !t.alive(q)) return;
        if (t.incomplete(q) || closer(dist2(t.position_at(q), pp), pid, t.dk2(q), t.dk_id(q)))
          marks.offer(q, p);
      };
      t.ball_candidates(pp, candidates);
      for (const std::uint32_t q : candidates) test(q);
    }
  }
};

struct PaperAnnulus {
  double dr = 0.1;     ///< radius step Δr (metres)
  double s_max = 2.0;  ///< largest search radius s_max (metres)

  void validate() const {
    if (!(dr > 0.0) || !std::isfinite(dr)) detail::invalid_argument("PaperAnnulus: dr must be > 0");
    if (!(s_max > 0.0) || !std::isfinite(s_max))
      detail::invalid_argument("PaperAnnulus: s_max must be finite and > 0");
    if (s_max / dr > 1e6)  // each step is a radius query; also keeps r += dr moving
      detail::invalid_argument("PaperAnnulus: s_max / dr must be at most 1e6");
  }

  template <class Tracker, class Marks>
  void collect(const Tracker& t, Marks& marks) const {
    std::vector<Point3d> centres;
    for (const std::uint32_t p : t.new_indices()) centres.push_back(t.position_at(p));
    for (const std::uint32_t p : t.removed_indices()) centres.push_back(t.position_at(p));
    std::vector<std::uint32_t> temp, previous;  // previous: sorted, for binary search
    for (const Point3d& c : centres) {          // Alg. 1, once per point of C_new and C_disappeared
      double r = dr;
      previous.clear();
      bool increase = false;
      do {
        increase = false;
        t.radius(c, r * r, temp);
        bool any = false;
        for (const std::uint32_t q : temp) {
          if (t.is_new(q) || std::binary_search(previous.begin(), previous.end(), q))
            continue;  // the annulus only, new points excluded (Alg. 1 line 7)
          any = true;
          if (t.marked(q)) continue;
          const double s_new = t.peek_s(q);
          const double s_old = t.s_at(q);
          const bool same = s_new == s_old || (std::isnan(s_new) && std::isnan(s_old));
          if (!same) {
            marks.mark(q);
            increase = true;
          }
        }
        if (!any) increase = true;
        if (increase) {
          r += dr;
          previous.swap(temp);
          std::sort(previous.begin(), previous.end());
        }
      } while (increase && r < s_max);
    }
  }
};

}  // namespace knnocc
