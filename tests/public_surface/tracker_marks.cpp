// expect: private
// A tracker's Marks cannot be made outside KnnTracker::apply.
#include <knnocc/knn/tracker.hpp>
int main() {
  knnocc::KnnTracker<> tracker;
  std::vector<std::uint32_t> out;
  knnocc::KnnTracker<>::Marks marks(tracker, out);
  marks.mark(0);
}
