#pragma once
// A small command-line parser for the knnocc tool: --name value pairs, --flags and (for commands
// that take them) positional arguments, with one-line errors (UsageError) for unknown options,
// missing values and malformed numbers.

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace knnocc::cli {

/// Bad command line: reported as "knnocc <command>: <message>", exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  /// `valued`: options that take a value; `flags`: options that do not; up to `max_positional`
  /// other arguments are kept in order (positional()).
  Args(const std::vector<std::string>& argv, const std::set<std::string>& valued,
       const std::set<std::string>& flags, std::size_t max_positional = 0) {
    for (std::size_t i = 0; i < argv.size(); ++i) {
      const std::string& a = argv[i];
      if (a == "-h" || a == "--help") {
        help_ = true;
        continue;
      }
      if (flags.count(a)) {
        flags_.insert(a);
      } else if (valued.count(a)) {
        if (i + 1 >= argv.size()) throw UsageError(a + " needs a value");
        if (values_.count(a)) throw UsageError(a + " given twice");
        values_[a] = argv[++i];
      } else if (a.rfind("--", 0) == 0) {
        throw UsageError("unknown option " + a + " (see --help)");
      } else if (positional_.size() < max_positional) {
        positional_.push_back(a);
      } else {
        throw UsageError("unexpected argument '" + a + "' (see --help)");
      }
    }
  }

  bool help() const { return help_; }
  const std::vector<std::string>& positional() const { return positional_; }
  bool flag(const std::string& name) const { return flags_.count(name) > 0; }
  bool has(const std::string& name) const { return values_.count(name) > 0; }

  std::string str(const std::string& name, const std::string& fallback = {}) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }
  std::string required(const std::string& name) const {
    if (!has(name)) throw UsageError(name + " is required (see --help)");
    return str(name);
  }
  double number(const std::string& name, double fallback) const {
    if (!has(name)) return fallback;
    const std::string& s = values_.at(name);
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
      throw UsageError(name + " expects a finite number, got '" + s + "'");
    return v;
  }
  long integer(const std::string& name, long fallback) const {
    if (!has(name)) return fallback;
    const std::string& s = values_.at(name);
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || errno == ERANGE)
      throw UsageError(name + " expects an integer, got '" + s + "'");
    return v;
  }

 private:
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
  bool help_ = false;
};

}  // namespace knnocc::cli
