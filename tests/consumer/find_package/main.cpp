// Downstream smoke test: the umbrella header must compile on its own.
#include <knnocc/knnocc.hpp>

#include <iostream>

int main() {
  std::cout << "knnocc " << knnocc::version_string << '\n';
  return 0;
}
