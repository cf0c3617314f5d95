#pragma once
// The command-line parser of the knnocc tool: `--name value` and `--name=value`, --flags, short
// forms of common options (-i --input, -o --out, -r --res, -k --k, -j --threads, -m --model, each
// where the command has the long option) and (for commands that take them) positional
// arguments, with one-line errors naming the option (UsageError): unknown options, missing
// values, an option given where a value belongs (`--out-voxels --threads 2`), malformed numbers.

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
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
    static const std::pair<const char*, const char*> kShort[] = {
        {"-i", "--input"}, {"-o", "--out"},     {"-r", "--res"},
        {"-k", "--k"},     {"-j", "--threads"}, {"-m", "--model"}};
    auto known = [&](const std::string& o) { return valued.count(o) || flags.count(o); };
    for (std::size_t i = 0; i < argv.size(); ++i) {
      std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        help_ = true;
        continue;
      }
      for (const auto& [s, l] : kShort)
        if (a == s && valued.count(l)) a = l;
      std::string inline_value;
      bool has_inline = false;
      const std::size_t eq = a.find('=');
      if (a.rfind("--", 0) == 0 && eq != std::string::npos) {
        inline_value = a.substr(eq + 1);
        a = a.substr(0, eq);
        has_inline = true;
      }
      if (flags.count(a)) {
        if (has_inline) throw UsageError(a + " takes no value");
        flags_.insert(a);
      } else if (valued.count(a)) {
        if (values_.count(a)) throw UsageError(a + " given twice");
        if (has_inline) {
          values_[a] = inline_value;
          continue;
        }
        if (i + 1 >= argv.size()) throw UsageError(a + " needs a value");
        const std::string& v = argv[i + 1];
        if (v.rfind("--", 0) == 0 && known(v.substr(0, v.find('='))))
          throw UsageError(a + " needs a value, got the option " + v);
        values_[a] = v;
        ++i;
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
