// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// KnnTracker: s_p for every map point and the normal distribution of the valid ones, kept up to
// date as the map point cloud changes (paper section 3.2, eq 5-12, Alg. 2).
//
//   s_p   = mean Euclidean distance from p to its k nearest neighbours in the map cloud (p itself
//           excluded; neighbours ordered by (distance, id), so the set is unique)
//   valid = s_p < s_limit; the valid s_p form N, S, mu, sigma (stats/welford.hpp)
//
// apply(change) is Alg. 2: disappeared points leave the distribution (eq 9-11), new points join
// it (eq 6-8), and every affected point (chosen by the AffectedPolicy, exact by default) is
// erased with its old s and added with its new one; sigma = sqrt(S/N) (eq 12).
//
// Defined behaviour:
//   - a point with fewer than k other points has no s (NaN) and is not in the distribution;
//     once the cloud is large enough it is handled as a new point (paper section 4.3);
//   - k larger than the cloud: every s is NaN, N == 0, mu == sigma == 0;
//   - duplicate positions: distance 0 is a valid neighbour distance (s may be 0);
//   - positions with a NaN/Inf coordinate (or beyond 1e150) in a change set are skipped and
//     counted;
//   - adding an id that exists, or removing/moving one that does not, is a caller error
//     (std::invalid_argument; abort without exceptions), detected before anything changes;
//     once a change set is accepted only std::bad_alloc can interrupt apply(), after which the
//     tracker must be discarded.
// Rounding: Welford erase accumulates error; after more erases than max(1024, N) since the last
// refresh, or an erase that cancels most of S, the distribution is recomputed exactly from the
// stored s values (amortised O(1)).
//
// Thread safety: const queries may run concurrently while apply() does not.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "../core/config.hpp"
#include "../stats/welford.hpp"
#include "affected.hpp"
#include "ball_grid.hpp"
#include "change_set.hpp"
#include "point_index.hpp"
#include "tracker_types.hpp"

namespace knnocc {

template <class AffectedPolicy = ExactReverseKnn>
class KnnTracker {
 public:
  using index_type = PointIndex::index_type;

  explicit KnnTracker(TrackerParams params = {}, AffectedPolicy policy = {})
      : params_(params), policy_(policy), points_(params.rebuild_min) {
    params_.validate();
    policy_.validate();  // every policy has one; all checks happen before any apply()
  }

  /// Alg. 2 for one change of the map point cloud.
  TrackerUpdate apply(const ChangeSet& change) {
    TrackerUpdate up;
    validate(change);
    new_.clear();
    removed_.clear();
    recompute_.clear();

    // Disappeared points (and the old place of moved ones) leave tree and distribution.
    auto take_out = [&](std::uint64_t id) {
      const index_type i = id_to_index_.at(id);
      id_to_index_.erase(id);
      removed_.push_back(i);
      erase_s(s_[i]);
      for (std::size_t j = 0; j < count_[i]; ++j) drop_reverse(nbr(i)[j], i);
      unregister_ball(i);
      points_.remove(i);
    };
    for (const std::uint64_t id : change.removed) {
      take_out(id);
      ++up.removed;
    }
    std::vector<const IdPoint*> incoming;
    for (const IdPoint& m : change.moved) {
      if (!finite(m.p)) {
        ++up.skipped_nonfinite;  // the point stays where it was
        continue;
      }
      take_out(m.id);
      incoming.push_back(&m);
      ++up.moved;
    }
    for (const IdPoint& a : change.added) {
      if (!finite(a.p)) {
        ++up.skipped_nonfinite;
        continue;
      }
      incoming.push_back(&a);
      ++up.added;
    }
    for (const IdPoint* a : incoming) {
      const index_type j = points_.append(a->id, a->p);
      grow(j);
      id_to_index_[a->id] = j;
      new_.push_back(j);
      is_new_[j] = 1;
    }
    points_.flush();

    // Affected points, judged against the state before this change.
    Marks marks(*this, recompute_);
    policy_.collect(static_cast<const KnnTracker&>(*this), marks);

    for (const index_type j : new_) {
      points_.knn(j, params_.k, scratch_);
      commit_neighbours(j);
      add_s(s_[j]);
    }
    // A pair can be offered twice (a ball registered in two cells of one level): keep one.
    std::sort(offers_.begin(), offers_.end());
    offers_.erase(std::unique(offers_.begin(), offers_.end()), offers_.end());
    for (const index_type q : recompute_) {
      const double old_s = s_[q];
      if (needs_query_[q])
        points_.knn(q, params_.k, scratch_);
      else
        merge_offers(q);
      if (commit_neighbours(q)) ++up.affected;
      if (!(old_s == s_[q] || (std::isnan(old_s) && std::isnan(s_[q])))) {
        erase_s(old_s);
        add_s(s_[q]);
      }
    }
    for (const index_type q : recompute_) marked_[q] = needs_query_[q] = 0;
    offers_.clear();
    for (const index_type j : new_) is_new_[j] = 0;
    for (const index_type r : removed_) rev_[r].clear();

    maintain();
    return up;
  }

  // ---- queries -------------------------------------------------------------------------------

  const TrackerParams& params() const { return params_; }
  std::size_t size() const { return points_.live(); }
  const RunningNormal& distribution() const { return dist_; }
  std::size_t N() const { return dist_.count(); }
  double mu() const { return dist_.mean(); }
  double sigma() const { return dist_.sigma(); }

  bool contains(std::uint64_t id) const { return id_to_index_.count(id) > 0; }
  /// s of a point (NaN while it has fewer than k neighbours); invalid_argument for unknown ids.
  double s(std::uint64_t id) const { return s_[index_of(id)]; }
  const Point3d& position(std::uint64_t id) const { return points_.position(index_of(id)); }
  /// The ids of a point's k nearest neighbours, nearest first.
  std::vector<std::uint64_t> neighbours(std::uint64_t id) const {
    const index_type i = index_of(id);
    std::vector<std::uint64_t> out;
    for (std::size_t j = 0; j < count_[i]; ++j) out.push_back(points_.id(nbr(i)[j]));
    return out;
  }
  /// Calls f(id, position, s) for every live point.
  template <class F>
  void for_each_point(F&& f) const {
    for (index_type i = 0; i < points_.size(); ++i)
      if (points_.alive(i)) f(points_.id(i), points_.position(i), s_[i]);
  }

  /// Recomputes N, mu, S exactly from the stored s values.
  void refresh_distribution() {
    std::vector<double> valid;
    valid.reserve(points_.live());
    for (index_type i = 0; i < points_.size(); ++i)
      if (points_.alive(i) && is_valid(s_[i])) valid.push_back(s_[i]);
    dist_.recompute(valid);
    erases_since_refresh_ = 0;
    refresh_pending_ = false;
  }

  std::size_t memory_usage() const {
    std::size_t bytes = points_.memory_usage() + nbr_.capacity() * sizeof(index_type) +
                        count_.capacity() * sizeof(std::uint32_t) +
                        (dk2_.capacity() + s_.capacity()) * sizeof(double) +
                        dk_id_.capacity() * sizeof(std::uint64_t) +
                        rev_.capacity() * sizeof(std::vector<index_type>) +
                        ball_r_.capacity() * sizeof(double) + balls_.memory_usage() +
                        marked_.capacity() + needs_query_.capacity() + is_new_.capacity() +
                        id_to_index_.size() * 32;
    for (const auto& r : rev_) bytes += r.capacity() * sizeof(index_type);
    return bytes;
  }

  // ---- policy interface (knn/affected.hpp) ---------------------------------------------------

  const std::vector<index_type>& new_indices() const { return new_; }
  const std::vector<index_type>& removed_indices() const { return removed_; }
  const std::vector<index_type>& reverse_neighbours(index_type i) const { return rev_[i]; }
  /// Every old point whose k-NN ball may contain p (a superset, possibly with repeats).
  void ball_candidates(const Point3d& p, std::vector<index_type>& out) const {
    out.clear();
    balls_.candidates(p, out);
  }
  std::size_t index_size() const { return points_.size(); }
  bool alive(index_type i) const { return points_.alive(i); }
  bool is_new(index_type i) const { return is_new_[i] != 0; }
  bool incomplete(index_type i) const { return count_[i] < params_.k; }
  double dk2(index_type i) const { return dk2_[i]; }
  std::uint64_t dk_id(index_type i) const { return dk_id_[i]; }
  const Point3d& position_at(index_type i) const { return points_.position(i); }
  std::uint64_t id_at(index_type i) const { return points_.id(i); }
  double s_at(index_type i) const { return s_[i]; }
  void radius(const Point3d& c, double r2, std::vector<index_type>& out) const {
    points_.radius(c, r2, out);
  }
  bool marked(index_type i) const { return marked_[i] != 0; }

  /// What an affected-point policy may change during apply(): which old points get new k-NN.
  /// Only apply() makes one, so nothing outside a policy's collect() can mark a point.
  class Marks {
   public:
    /// q's k-NN must be searched again (it may have lost a neighbour, or the policy cannot tell).
    void mark(index_type q) { t_->mark(q, *out_); }
    /// New point p beats q's k-th neighbour; unless q is also marked, its new k-NN are the best k
    /// of its old ones and the points offered to it.
    void offer(index_type q, index_type p) { t_->offer(q, p, *out_); }

   private:
    friend class KnnTracker;
    Marks(KnnTracker& t, std::vector<index_type>& out) : t_(&t), out_(&out) {}
    KnnTracker* t_;
    std::vector<index_type>* out_;
  };
  /// s of point i against the current cloud, without storing anything.
  double peek_s(index_type i) const {
    std::vector<Neighbor> nb;
    points_.knn(i, params_.k, nb);
    return mean_distance(nb);
  }

 private:
  // Marks::mark and Marks::offer (a policy's collect()).
  void mark(index_type i, std::vector<index_type>& out) {
    needs_query_[i] = 1;
    if (marked_[i]) return;
    marked_[i] = 1;
    out.push_back(i);
  }
  void offer(index_type i, index_type p, std::vector<index_type>& out) {
    offers_.emplace_back(i, p);
    if (marked_[i]) return;
    marked_[i] = 1;
    out.push_back(i);
  }

  // Beyond 1e150 m squared distances overflow to +inf and the trees could not order them.
  static bool finite(const Point3d& p) {
    return std::fabs(p.x) <= 1e150 && std::fabs(p.y) <= 1e150 && std::fabs(p.z) <= 1e150;
  }
  bool is_valid(double s) const { return !std::isnan(s) && s < params_.s_limit; }
  index_type index_of(std::uint64_t id) const {
    auto it = id_to_index_.find(id);
    if (it == id_to_index_.end())
      detail::invalid_argument("unknown map point id " + std::to_string(id));
    return it->second;
  }
  index_type* nbr(index_type i) { return &nbr_[static_cast<std::size_t>(i) * params_.k]; }
  const index_type* nbr(index_type i) const {
    return &nbr_[static_cast<std::size_t>(i) * params_.k];
  }

  double mean_distance(const std::vector<Neighbor>& nb) const {
    if (nb.size() < params_.k) return std::numeric_limits<double>::quiet_NaN();
    double sum = 0.0;
    for (const Neighbor& n : nb) sum += std::sqrt(n.d2);
    return sum / static_cast<double>(params_.k);
  }

  void validate(const ChangeSet& c) const {
    std::unordered_set<std::uint64_t> seen;
    for (const std::uint64_t id : c.removed)
      if (!contains(id) || !seen.insert(id).second)
        detail::invalid_argument("removed id " + std::to_string(id) +
                                 " is not in the map (or listed twice)");
    for (const IdPoint& m : c.moved)
      if (!contains(m.id) || !seen.insert(m.id).second)
        detail::invalid_argument("moved id " + std::to_string(m.id) +
                                 " is not in the map (or listed twice)");
    for (const IdPoint& a : c.added)
      if (contains(a.id) || !seen.insert(a.id).second)
        detail::invalid_argument("added id " + std::to_string(a.id) +
                                 " is already in the map (or listed twice)");
  }

  void grow(index_type j) {
    const std::size_t n = static_cast<std::size_t>(j) + 1;
    nbr_.resize(n * params_.k);
    count_.resize(n, 0);
    dk2_.resize(n, 0.0);
    dk_id_.resize(n, 0);
    s_.resize(n, std::numeric_limits<double>::quiet_NaN());
    rev_.resize(n);
    ball_r_.resize(n, std::numeric_limits<double>::quiet_NaN());
    marked_.resize(n, 0);
    needs_query_.resize(n, 0);
    is_new_.resize(n, 0);
  }

  void drop_reverse(index_type owner, index_type who) {
    if (!points_.alive(owner)) return;
    auto& r = rev_[owner];
    auto it = std::find(r.begin(), r.end(), who);
    if (it != r.end()) {
      *it = r.back();
      r.pop_back();
    }
  }

  // Old k-NN of i plus the new points offered to it, best k by (d2, id): the exact new k-NN when
  // none of the old ones was removed (ExactReverseKnn's insertion rule found every candidate).
  void merge_offers(index_type i) {
    scratch_.clear();
    const Point3d& pi = points_.position(i);
    auto push = [&](index_type j) {
      scratch_.push_back(Neighbor{j, points_.id(j), dist2(pi, points_.position(j))});
    };
    for (std::size_t j = 0; j < count_[i]; ++j) push(nbr(i)[j]);
    auto it = std::lower_bound(offers_.begin(), offers_.end(), std::make_pair(i, index_type{0}));
    for (; it != offers_.end() && it->first == i; ++it) push(it->second);
    std::sort(scratch_.begin(), scratch_.end(),
              [](const Neighbor& a, const Neighbor& b) { return closer(a.d2, a.id, b.d2, b.id); });
    if (scratch_.size() > params_.k) scratch_.resize(params_.k);
  }

  // Stores scratch_ as i's neighbours (with s, d_k, reverse lists, its ball); returns true
  // when the set changed.
  bool commit_neighbours(index_type i) {
    bool changed = scratch_.size() != count_[i];
    for (std::size_t j = 0; !changed && j < scratch_.size(); ++j)
      changed = nbr(i)[j] != scratch_[j].index;
    if (changed) {
      for (std::size_t j = 0; j < count_[i]; ++j) drop_reverse(nbr(i)[j], i);
      for (std::size_t j = 0; j < scratch_.size(); ++j) {
        nbr(i)[j] = scratch_[j].index;
        rev_[scratch_[j].index].push_back(i);
      }
      count_[i] = static_cast<std::uint32_t>(scratch_.size());
    }
    dk2_[i] = scratch_.empty() ? 0.0 : scratch_.back().d2;
    dk_id_[i] = scratch_.empty() ? 0 : scratch_.back().id;
    s_[i] = mean_distance(scratch_);  // eq 5's s for this point
    register_ball(i);
    return changed;
  }

  void add_s(double s) {
    if (is_valid(s)) dist_.add(s);  // eq 6-8
  }
  void erase_s(double s) {
    if (!is_valid(s)) return;
    const double before = dist_.sum_squares();
    dist_.erase(s);  // eq 9-11
    ++erases_since_refresh_;
    // Erasing a value far from the rest cancels most of S (eq 10) and with it its precision.
    if (dist_.sum_squares() < 1e-3 * before) refresh_pending_ = true;
  }

  // ---- k-NN balls (knn/ball_grid.hpp): where a new point can change this one's k-NN --------

  double ball_radius(index_type i) const {
    return incomplete(i) ? std::numeric_limits<double>::infinity() : std::sqrt(dk2_[i]);
  }
  // The registered ball may be larger than the true one (candidates are tested exactly), so a
  // ball that shrank by less than half keeps its registration: most affected points only shrink.
  void register_ball(index_type i) {
    const double r = ball_radius(i);
    const double reg = ball_r_[i];
    if (r <= reg && r >= 0.5 * reg) return;  // NaN reg (none yet) fails both tests
    unregister_ball(i);
    balls_.insert(i, points_.position(i), r);
    ball_r_[i] = r;
  }
  void unregister_ball(index_type i) {
    if (std::isnan(ball_r_[i])) return;
    balls_.erase(i, points_.position(i), ball_r_[i]);
    ball_r_[i] = std::numeric_limits<double>::quiet_NaN();
  }

  // After each apply: keep the distribution exact enough and the dataset free of piles of dead
  // entries.
  void maintain() {
    if (refresh_pending_ || erases_since_refresh_ > std::max<std::size_t>(1024, dist_.count()))
      refresh_distribution();
    if (points_.dead() > params_.compact_min_dead && points_.dead() > points_.live()) compact();
  }

  void compact() {
    const std::vector<index_type> remap = points_.compact();
    const std::size_t n = points_.size(), k = params_.k;
    std::vector<index_type> nbr(n * k);
    std::vector<std::uint32_t> count(n);
    std::vector<double> dk2(n), s(n);
    std::vector<std::uint64_t> dk_id(n);
    std::vector<std::vector<index_type>> rev(n);
    for (std::size_t old = 0; old < remap.size(); ++old) {
      const index_type i = remap[old];
      if (i == PointIndex::npos) continue;
      std::size_t c = 0;
      for (std::size_t j = 0; j < count_[old]; ++j) {
        const index_type m = remap[nbr_[old * k + j]];
        if (m != PointIndex::npos) nbr[i * k + c++] = m;  // dead ones only under PaperAnnulus
      }
      count[i] = static_cast<std::uint32_t>(c);
      dk2[i] = dk2_[old];
      dk_id[i] = dk_id_[old];
      s[i] = s_[old];
      for (const index_type r : rev_[old])
        if (remap[r] != PointIndex::npos) rev[i].push_back(remap[r]);
    }
    nbr_.swap(nbr);
    count_.swap(count);
    dk2_.swap(dk2);
    dk_id_.swap(dk_id);
    s_.swap(s);
    rev_.swap(rev);
    marked_.assign(n, 0);
    needs_query_.assign(n, 0);
    is_new_.assign(n, 0);
    for (auto& [id, idx] : id_to_index_) idx = remap[idx];
    balls_.clear();
    ball_r_.assign(n, std::numeric_limits<double>::quiet_NaN());
    for (index_type i = 0; i < n; ++i) register_ball(i);
  }

  TrackerParams params_;
  AffectedPolicy policy_;
  PointIndex points_;
  std::unordered_map<std::uint64_t, index_type> id_to_index_;
  // Per dataset index:
  std::vector<index_type> nbr_;               // k neighbour indices each, nearest first
  std::vector<std::uint32_t> count_;          // how many of them exist (< k: incomplete)
  std::vector<double> dk2_;                   // squared distance of the k-th (last) neighbour
  std::vector<std::uint64_t> dk_id_;          // id of the k-th neighbour
  std::vector<double> s_;                     // eq 5's s, NaN when incomplete
  std::vector<std::vector<index_type>> rev_;  // points that have this one among their k-NN
  std::vector<double> ball_r_;                // radius its k-NN ball is registered with (NaN: none)
  std::vector<std::uint8_t> marked_, needs_query_, is_new_;
  // The distribution and the insertion search radius.
  RunningNormal dist_;
  std::size_t erases_since_refresh_ = 0;
  bool refresh_pending_ = false;
  detail::BallGrid balls_;
  // Per apply():
  std::vector<index_type> new_, removed_, recompute_;
  std::vector<std::pair<index_type, index_type>> offers_;  // (point, new point it should consider)
  std::vector<Neighbor> scratch_;
};

}  // namespace knnocc
