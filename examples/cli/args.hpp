#pragma once
// The knnocc tool's options, each declared once (Option): its name and short form, the value it
// takes, its help text, its default and the range or choices it must be in. A command's options
// (CommandSpec) give both the parser (Args) and the help (help_text.hpp: `--help` and
// docs/cli.md), so the two cannot drift apart.
//
// Args parses `--name value`, `--name=value`, flags, the short forms a command declares and (for
// commands that take them) positional arguments, and checks every given value against its
// declaration before the command runs. Errors are one line naming the option (UsageError):
// unknown options, missing values, an option given where a value belongs (`--out-voxels
// --threads 2`), malformed numbers, values out of range, unknown choices.

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
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

/// A number as --help shows it ("%g": 0.3, 1e-04, 4096).
inline std::string format_number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", v);
  return s;
}

/// What an option's value is: checked and converted when the command line is parsed.
enum class ValueType { flag, text, number, integer, size };

/// One option of a command, declared once. Built with the named constructors and refined with
/// the chained setters, e.g.
///   Option::number("--res", "R", "voxel edge in metres").alias("-r").at_least(1e-4)
class Option {
 public:
  static Option flag(std::string name, std::string help) {
    return Option(std::move(name), ValueType::flag, "", std::move(help));
  }
  static Option text(std::string name, std::string value, std::string help) {
    return Option(std::move(name), ValueType::text, std::move(value), std::move(help));
  }
  static Option number(std::string name, std::string value, std::string help) {
    return Option(std::move(name), ValueType::number, std::move(value), std::move(help));
  }
  static Option integer(std::string name, std::string value, std::string help) {
    return Option(std::move(name), ValueType::integer, std::move(value), std::move(help));
  }
  /// A memory size such as 800M or 4G (decimal units K M G T, optional B), at least 16M.
  static Option size(std::string name, std::string value, std::string help) {
    return Option(std::move(name), ValueType::size, std::move(value), std::move(help));
  }

  /// A short form such as "-r".
  Option& alias(std::string short_form) {
    short_ = std::move(short_form);
    return *this;
  }
  /// The value used when the option is not given, as a user would write it.
  Option& fallback(std::string value) {
    default_ = std::move(value);
    return *this;
  }
  /// The default described in words, when it is not a fixed value ("from the map").
  Option& fallback_text(std::string words) {
    default_words_ = std::move(words);
    return *this;
  }
  Option& required() {
    required_ = true;
    return *this;
  }
  Option& at_least(double v) { return bound(lo_, lo_open_, v, false); }
  Option& above(double v) { return bound(lo_, lo_open_, v, true); }
  Option& at_most(double v) { return bound(hi_, hi_open_, v, false); }
  Option& below(double v) { return bound(hi_, hi_open_, v, true); }
  /// A rule the bounds cannot say, in words for the help ("> 0, or < 0 for no limit").
  Option& satisfies(std::string words, bool (*ok)(double)) {
    rule_words_ = std::move(words);
    rule_ = ok;
    return *this;
  }
  /// The only values a text option takes.
  Option& one_of(std::vector<std::string> choices) {
    choices_ = std::move(choices);
    return *this;
  }

  const std::string& name() const { return name_; }
  const std::string& short_form() const { return short_; }
  const std::string& value_name() const { return value_; }
  const std::string& help() const { return help_; }
  ValueType type() const { return type_; }
  bool takes_value() const { return type_ != ValueType::flag; }
  bool is_required() const { return required_; }
  const std::string& default_value() const { return default_; }
  const std::vector<std::string>& choices() const { return choices_; }

  /// The default as help shows it: the value, the words, or "".
  std::string default_shown() const { return default_.empty() ? default_words_ : default_; }

  /// The allowed values in words: "> 0", "in [1, 4096]", "octomap, knn or robust", or "".
  std::string range_text() const {
    if (!choices_.empty()) return join_choices();
    if (rule_) return rule_words_;
    const bool has_lo = lo_ > -kInf, has_hi = hi_ < kInf;
    if (has_lo && has_hi)
      return "in " + std::string(lo_open_ ? "(" : "[") + format_number(lo_) + ", " +
             format_number(hi_) + (hi_open_ ? ")" : "]");
    if (has_lo) return (lo_open_ ? "> " : ">= ") + format_number(lo_);
    if (has_hi) return (hi_open_ ? "< " : "<= ") + format_number(hi_);
    return "";
  }

  /// Checks one given value: its type, range and choices; UsageError naming the option.
  void check(const std::string& v) const {
    if (type_ == ValueType::text) {
      if (!choices_.empty() && !is_choice(v))
        throw UsageError(name_ + " must be " + join_choices() + ", got '" + v + "'");
      return;
    }
    if (type_ == ValueType::size) {
      parse_size(v);
      return;
    }
    const double x =
        type_ == ValueType::integer ? static_cast<double>(parse_integer(v)) : parse_number(v);
    const bool ok =
        (lo_open_ ? x > lo_ : x >= lo_) && (hi_open_ ? x < hi_ : x <= hi_) && (!rule_ || rule_(x));
    if (!ok) throw UsageError(name_ + " must be " + range_text() + ", got " + v);
  }

  double parse_number(const std::string& s) const {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
      throw UsageError(name_ + " expects a finite number, got '" + s + "'");
    return v;
  }
  long parse_integer(const std::string& s) const {
    char* end = nullptr;
    errno = 0;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || errno == ERANGE)
      throw UsageError(name_ + " expects an integer, got '" + s + "'");
    return v;
  }
  /// "2G", "512M", "1.5GB", "800000000" in bytes.
  double parse_size(const std::string& s) const {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    std::string unit(end ? end : "");
    for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (!unit.empty() && unit.back() == 'B') unit.pop_back();
    const double scale = unit.empty()  ? 1
                         : unit == "K" ? 1e3
                         : unit == "M" ? 1e6
                         : unit == "G" ? 1e9
                         : unit == "T" ? 1e12
                                       : 0;
    if (s.empty() || end == s.c_str() || scale == 0 || !std::isfinite(v) || v * scale < 16e6)
      throw UsageError(name_ + " expects a size of at least 16M such as 800M or 4G, got '" + s +
                       "'");
    return v * scale;
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  Option(std::string name, ValueType type, std::string value, std::string help)
      : name_(std::move(name)), value_(std::move(value)), help_(std::move(help)), type_(type) {}

  Option& bound(double& at, bool& open, double v, bool is_open) {
    at = v;
    open = is_open;
    return *this;
  }
  bool is_choice(const std::string& v) const {
    for (const auto& c : choices_)
      if (c == v) return true;
    return false;
  }
  std::string join_choices() const {
    std::string s;
    for (std::size_t i = 0; i < choices_.size(); ++i)
      s += (i == 0 ? "" : i + 1 == choices_.size() ? " or " : ", ") + choices_[i];
    return s;
  }

  std::string name_, short_, value_, help_, default_, default_words_, rule_words_;
  bool (*rule_)(double) = nullptr;
  std::vector<std::string> choices_;
  ValueType type_;
  bool required_ = false;
  double lo_ = -kInf, hi_ = kInf;
  bool lo_open_ = false, hi_open_ = false;
};

/// Options under one heading of a command's help ("options", "k-NN model (--model knn)").
struct OptionGroup {
  std::string title;
  std::vector<Option> options;
  /// Text printed under the heading, before the options (may be empty).
  std::string text;
};

/// Everything `--help` and docs/cli.md say about one command, and what its parser accepts.
struct CommandSpec {
  std::string name;     ///< "map", or "demo --scene room" for a variant
  std::string summary;  ///< one line for `knnocc --help`
  std::string usage;    ///< the usage lines, without "usage: "
  std::string text;     ///< what the command does and prints (preformatted)
  std::vector<OptionGroup> groups;
  std::string footer;                ///< preformatted text after the options (may be empty)
  std::size_t max_positional = 0;    ///< positional arguments taken (IN OUT, MAP...)
  std::string positional_limit_why;  ///< why there are at most max_positional of them
};

class Args {
 public:
  /// Parses `argv` (the words after the command's name) against `spec`; every given value is
  /// checked against its option's declaration.
  Args(const CommandSpec& spec, const std::vector<std::string>& argv) : spec_(&spec) {
    for (const OptionGroup& g : spec.groups)
      for (const Option& o : g.options) options_.emplace(o.name(), &o);
    parse(argv);
    if (help_) return;
    for (const auto& [name, value] : values_) option(name).check(value);
    for (const auto& [name, o] : options_)
      if (o->is_required() && !values_.count(name))
        throw UsageError(name + " is required (see --help)");
  }

  const CommandSpec& spec() const { return *spec_; }
  bool help() const { return help_; }
  const std::vector<std::string>& positional() const { return positional_; }
  bool flag(const std::string& name) const {
    option(name);
    return flags_.count(name) > 0;
  }
  bool has(const std::string& name) const {
    option(name);
    return values_.count(name) > 0;
  }

  /// The given value, else the declared default, else `fallback`.
  std::string str(const std::string& name, const std::string& fallback = {}) const {
    const Option& o = option(name);
    auto it = values_.find(name);
    if (it != values_.end()) return it->second;
    return o.default_value().empty() ? fallback : o.default_value();
  }
  std::string required(const std::string& name) const {
    if (!has(name)) throw UsageError(name + " is required (see --help)");
    return str(name);
  }
  /// The given or declared value; `fallback` when neither exists (a default computed by the
  /// command, e.g. from the input).
  double number(const std::string& name, double fallback = kNone) const {
    const std::string v = str(name);
    if (!v.empty()) return option(name).parse_number(v);
    return or_missing(name, fallback);
  }
  long integer(const std::string& name, long fallback = kNoInteger) const {
    const std::string v = str(name);
    if (!v.empty()) return option(name).parse_integer(v);
    if (fallback == kNoInteger) missing(name);
    return fallback;
  }
  double size(const std::string& name, double fallback = kNone) const {
    const std::string v = str(name);
    if (!v.empty()) return option(name).parse_size(v);
    return or_missing(name, fallback);
  }

 private:
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  static constexpr long kNoInteger = std::numeric_limits<long>::min();

  /// The declaration of `name`; asking for an undeclared option is a bug in the tool.
  const Option& option(const std::string& name) const {
    auto it = options_.find(name);
    if (it == options_.end())
      throw std::logic_error("knnocc " + spec_->name + ": option " + name + " is not declared");
    return *it->second;
  }
  double or_missing(const std::string& name, double fallback) const {
    if (std::isnan(fallback)) missing(name);
    return fallback;
  }
  [[noreturn]] void missing(const std::string& name) const {
    throw std::logic_error("knnocc " + spec_->name + ": " + name + " has no value or default");
  }

  const Option* find(const std::string& word) const {
    for (const auto& [name, o] : options_)
      if (word == name || (!o->short_form().empty() && word == o->short_form())) return o;
    return nullptr;
  }

  void parse(const std::vector<std::string>& argv) {
    for (std::size_t i = 0; i < argv.size(); ++i) {
      std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        help_ = true;
        continue;
      }
      std::string inline_value;
      bool has_inline = false;
      const std::size_t eq = a.find('=');
      if (a.rfind("--", 0) == 0 && eq != std::string::npos) {
        inline_value = a.substr(eq + 1);
        a = a.substr(0, eq);
        has_inline = true;
      }
      const Option* o = find(a);
      if (o && !o->takes_value()) {
        if (has_inline) throw UsageError(o->name() + " takes no value");
        flags_.insert(o->name());
      } else if (o) {
        if (values_.count(o->name())) throw UsageError(o->name() + " given twice");
        if (has_inline) {
          values_[o->name()] = inline_value;
          continue;
        }
        if (i + 1 >= argv.size()) throw UsageError(o->name() + " needs a value");
        const std::string& v = argv[i + 1];
        if (v.rfind("--", 0) == 0 && find(v.substr(0, v.find('='))))
          throw UsageError(o->name() + " needs a value, got the option " + v);
        values_[o->name()] = v;
        ++i;
      } else if (a.rfind("--", 0) == 0) {
        throw UsageError("unknown option " + a + " (see --help)");
      } else if (positional_.size() < spec_->max_positional) {
        positional_.push_back(a);
      } else if (spec_->max_positional > 0 && !spec_->positional_limit_why.empty()) {
        throw UsageError("at most " + std::to_string(spec_->max_positional) + " " +
                         spec_->positional_limit_why + "; '" + a + "' is one too many");
      } else {
        throw UsageError("unexpected argument '" + a + "' (see --help)");
      }
    }
  }

  const CommandSpec* spec_;
  std::map<std::string, const Option*> options_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
  bool help_ = false;
};

}  // namespace knnocc::cli
