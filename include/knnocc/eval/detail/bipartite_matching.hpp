// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Maximum bipartite matching (Hopcroft-Karp) for the one-to-one counting of eval/confusion.hpp.
// augment(allowed) grows the current matching to a maximum one among the edges whose right vertex
// `allowed` accepts. An augmenting path never unmatches a matched vertex, so a second call with a
// larger set keeps every right vertex the first call matched: the result is a maximum matching
// of the larger graph that covers as many right vertices of the first set as any matching can.
// Paths are walked with an explicit stack (a path can be as long as the graph).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace knnocc::eval::detail {

class BipartiteMatching {
 public:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

  /// Left vertex u's edges are adj[offsets[u] .. offsets[u + 1]) (right vertex indices).
  BipartiteMatching(std::size_t right, std::vector<std::uint32_t> offsets,
                    std::vector<std::uint32_t> adj)
      : offsets_(std::move(offsets)),
        adj_(std::move(adj)),
        match_left_(offsets_.empty() ? 0 : offsets_.size() - 1, kNone),
        match_right_(right, kNone) {}

  std::size_t left() const { return match_left_.size(); }
  std::uint32_t match_of_left(std::size_t u) const { return match_left_[u]; }
  std::uint32_t match_of_right(std::size_t v) const { return match_right_[v]; }
  std::size_t size() const {
    std::size_t n = 0;
    for (const std::uint32_t v : match_left_) n += v != kNone;
    return n;
  }

  /// Augments until no augmenting path over allowed right vertices is left.
  template <class Allowed>
  void augment(const Allowed& allowed) {
    for (std::size_t u = 0; u < left(); ++u)  // paths of one edge first: far fewer phases
      for (std::uint32_t e = offsets_[u]; e < offsets_[u + 1] && match_left_[u] == kNone; ++e)
        if (allowed(adj_[e]) && match_right_[adj_[e]] == kNone) {
          match_left_[u] = adj_[e];
          match_right_[adj_[e]] = static_cast<std::uint32_t>(u);
        }
    while (layer(allowed))
      for (std::size_t u = 0; u < left(); ++u)
        if (match_left_[u] == kNone) path_from(static_cast<std::uint32_t>(u), allowed);
  }

 private:
  static constexpr std::uint32_t kInf = std::numeric_limits<std::uint32_t>::max();

  // BFS layers from the free left vertices; true when a free right vertex is reachable.
  template <class Allowed>
  bool layer(const Allowed& allowed) {
    dist_.assign(left(), kInf);
    queue_.clear();
    for (std::size_t u = 0; u < left(); ++u)
      if (match_left_[u] == kNone) {
        dist_[u] = 0;
        queue_.push_back(static_cast<std::uint32_t>(u));
      }
    bool found = false;
    for (std::size_t h = 0; h < queue_.size(); ++h) {
      const std::uint32_t u = queue_[h];
      for (std::uint32_t e = offsets_[u]; e < offsets_[u + 1]; ++e) {
        const std::uint32_t v = adj_[e];
        if (!allowed(v)) continue;
        const std::uint32_t w = match_right_[v];
        if (w == kNone) {
          found = true;
        } else if (dist_[w] == kInf) {
          dist_[w] = dist_[u] + 1;
          queue_.push_back(w);
        }
      }
    }
    next_.assign(offsets_.begin(), offsets_.end() - 1);
    return found;
  }

  // One shortest augmenting path from the free vertex u along the layers (depth-first).
  template <class Allowed>
  void path_from(std::uint32_t u, const Allowed& allowed) {
    stack_.clear();
    stack_.push_back(u);
    while (!stack_.empty()) {
      const std::uint32_t x = stack_.back();
      if (next_[x] == offsets_[x + 1]) {  // dead end: never again in this phase
        dist_[x] = kInf;
        stack_.pop_back();
        if (!stack_.empty()) ++next_[stack_.back()];
        continue;
      }
      const std::uint32_t v = adj_[next_[x]];
      const std::uint32_t w = allowed(v) ? match_right_[v] : x;  // x: skip the edge
      if (w == kNone) {                                          // free right vertex: flip the path
        for (const std::uint32_t s : stack_) {
          const std::uint32_t sv = adj_[next_[s]];
          match_left_[s] = sv;
          match_right_[sv] = s;
        }
        return;
      }
      if (w != x && dist_[w] == dist_[x] + 1)
        stack_.push_back(w);
      else
        ++next_[x];
    }
  }

  std::vector<std::uint32_t> offsets_, adj_;
  std::vector<std::uint32_t> match_left_, match_right_;
  std::vector<std::uint32_t> dist_, queue_, next_, stack_;
};

}  // namespace knnocc::eval::detail
