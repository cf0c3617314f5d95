// expect: private
// Only an affected-point policy, through the Marks that apply() hands it, marks a point.
#include <knnocc/knn/tracker.hpp>
int main() {
  knnocc::KnnTracker<> tracker;
  std::vector<std::uint32_t> out;
  tracker.mark(0, out);
}
