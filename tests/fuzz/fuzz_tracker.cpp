// The k-NN tracker driven by a byte stream of add / remove / move operations (positions on a
// coarse grid, so ties and duplicates are common), checked against brute force after every
// change set: k-NN sets, s_p, N, mu and sigma.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <knnocc/knn/tracker.hpp>

#include "../knn_truth.hpp"

namespace {

struct Bytes {
  const std::uint8_t* p;
  std::size_t n;
  bool take(std::uint8_t& b) {
    if (!n) return false;
    b = *p++;
    --n;
    return true;
  }
};

void fail(const char* what) {
  std::fprintf(stderr, "tracker differs from brute force: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in{data, size};
  std::uint8_t b = 0;
  if (!in.take(b)) return 0;
  knnocc::TrackerParams params;
  params.k = 1 + b % 6;
  params.s_limit = (b & 0x80) ? 1.5 : INFINITY;
  params.compact_min_dead = 4;  // exercise compaction and static rebuilds on small clouds
  params.rebuild_min = 4;
  knnocc::KnnTracker<> tracker(params);
  knnocc::test::Cloud cloud;
  std::uint64_t next_id = 0;
  while (in.n) {
    knnocc::ChangeSet cs;
    std::uint8_t ops = 0;
    if (!in.take(ops)) break;
    std::vector<std::uint64_t> touched;
    for (int i = 0; i < 1 + ops % 8; ++i) {
      std::uint8_t op = 0, x = 0, y = 0;
      if (!in.take(op) || !in.take(x) || !in.take(y)) break;
      const knnocc::Point3d p{(x % 16) * 0.25, (y % 16) * 0.25, ((x ^ y) % 4) * 0.25};
      auto pick = [&]() -> const std::uint64_t* {  // an existing id not yet in this change set
        if (cloud.empty()) return nullptr;
        auto it = cloud.begin();
        std::advance(it, static_cast<long>(op) % static_cast<long>(cloud.size()));
        for (std::uint64_t t : touched)
          if (t == it->first) return nullptr;
        touched.push_back(it->first);
        return &it->first;
      };
      if (op % 3 == 0 || cloud.empty()) {
        cs.added.push_back({next_id++, p});
      } else if (const std::uint64_t* id = pick()) {
        if (op % 3 == 1)
          cs.removed.push_back(*id);
        else
          cs.moved.push_back({*id, p});
      }
    }
    tracker.apply(cs);
    for (const std::uint64_t id : cs.removed) cloud.erase(id);
    for (const auto& m : cs.moved) cloud[m.id] = m.p;
    for (const auto& a : cs.added) cloud[a.id] = a.p;
    const knnocc::test::Truth t = knnocc::test::brute_force(cloud, params.k, params.s_limit);
    if (tracker.size() != cloud.size()) fail("size");
    for (const auto& [id, p] : cloud) {
      if (tracker.neighbours(id) != t.knn.at(id)) fail("k-NN set");
      const double a = tracker.s(id), e = t.s.at(id);
      if (!(a == e || (std::isnan(a) && std::isnan(e)))) fail("s");
    }
    if (tracker.N() != t.n) fail("N");
    // Welford's rounding is relative to the data's scale (s up to ~5 m here), not to sigma.
    const double scale = std::max({std::fabs(t.mean), t.sigma, 1e-12});
    if (!(std::fabs(tracker.mu() - t.mean) <= 1e-9 * scale)) fail("mu");
    if (!(std::fabs(tracker.sigma() - t.sigma) <= 1e-9 * scale)) fail("sigma");
  }
  return 0;
}
