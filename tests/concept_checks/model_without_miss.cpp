// expect: needs `float miss_logodds\(\) const`
#include <knnocc/mapper.hpp>
struct Model {
  float hit_logodds() const { return 0.85f; }
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
