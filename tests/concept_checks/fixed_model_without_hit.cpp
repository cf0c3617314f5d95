// expect: needs `float hit_logodds\(\) const`
#include <knnocc/mapper.hpp>
struct Model {
  float miss_logodds() const { return -0.4f; }
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
