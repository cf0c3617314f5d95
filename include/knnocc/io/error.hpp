#pragma once
// knnocc::io::Error: the one exception type the IO layer throws.

#include <stdexcept>
#include <string>

namespace knnocc::io {

// what() is "<file>: <problem>" so a log line alone tells which input is bad.
class Error : public std::runtime_error {
 public:
  Error(const std::string& file, const std::string& problem)
      : std::runtime_error(file + ": " + problem), file_(file), problem_(problem) {}

  const std::string& file() const noexcept { return file_; }
  const std::string& problem() const noexcept { return problem_; }

 private:
  std::string file_;
  std::string problem_;
};

}  // namespace knnocc::io
