// The tool's option declarations and parser (examples/cli/args.hpp), the help generated from
// them (help_text.hpp) and the command table (commands.hpp): every declared default passes its
// own check, help lines fit, and the parser refuses what the declarations refuse.

#include <doctest/doctest.h>

#ifdef KNNOCC_TEST_TOOL_HEADERS

#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "help_text.hpp"

namespace cli = knnocc::cli;

namespace {

bool ok_not_zero(double v) { return v != 0.0; }

cli::CommandSpec test_spec() {
  cli::CommandSpec s;
  s.name = "test";
  s.summary = "a command for the tests";
  s.usage = "knnocc test [options]";
  s.groups.push_back(
      {"options",
       {cli::Option::text("--input", "PATH", "input").alias("-i").required(),
        cli::Option::number("--res", "R", "voxel edge").alias("-r").fallback("0.1").above(0),
        cli::Option::integer("--k", "K", "neighbours").fallback("8").at_least(1).at_most(4096),
        cli::Option::number("--max-range", "M", "range").satisfies("> 0, or < 0", ok_not_zero),
        cli::Option::text("--model", "NAME", "model")
            .fallback("octomap")
            .one_of({"octomap", "knn"}),
        cli::Option::size("--memory-limit", "SIZE", "limit"),
        cli::Option::flag("--discretize", "a flag")},
       ""});
  s.max_positional = 2;
  s.positional_limit_why = "files";
  return s;
}

std::string usage_error(const cli::CommandSpec& spec, const std::vector<std::string>& argv) {
  try {
    const cli::Args args(spec, argv);
  } catch (const cli::UsageError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("args: values, defaults and short forms") {
  const cli::CommandSpec spec = test_spec();
  const cli::Args a(spec, {"-i", "in.ply", "--res=0.05", "--discretize", "a", "b"});
  CHECK(a.str("--input") == "in.ply");
  CHECK(a.number("--res") == doctest::Approx(0.05));
  CHECK(a.integer("--k") == 8);  // the declared default
  CHECK(a.str("--model") == "octomap");
  CHECK(a.flag("--discretize"));
  CHECK_FALSE(a.has("--max-range"));
  CHECK(a.number("--max-range", -1.0) == -1.0);  // a default the command computes
  CHECK(a.positional() == std::vector<std::string>{"a", "b"});
  CHECK(cli::Args(spec, {"-i", "x", "--memory-limit", "1.5G"}).size("--memory-limit") == 1.5e9);
  // Asking for an option the command never declared is a bug in the tool, not a usage error.
  CHECK_THROWS_AS(a.has("--undeclared"), std::logic_error);
  CHECK_THROWS_AS(a.number("--memory-limit"), std::logic_error);  // neither given nor defaulted
  CHECK(cli::Args(spec, {"--help"}).help());                      // --help needs no required option
}

TEST_CASE("args: every declared check refuses with one line naming the option") {
  const cli::CommandSpec spec = test_spec();
  auto err = [&](std::vector<std::string> argv) {
    argv.insert(argv.begin(), {"-i", "x"});
    return usage_error(spec, argv);
  };
  CHECK(usage_error(spec, {}) == "--input is required (see --help)");
  CHECK(err({"--res", "0"}) == "--res must be > 0, got 0");
  CHECK(err({"--res", "nan"}) == "--res expects a finite number, got 'nan'");
  CHECK(err({"--res", "1e999"}) == "--res expects a finite number, got '1e999'");
  CHECK(err({"--k", "4097"}) == "--k must be in [1, 4096], got 4097");
  CHECK(err({"--k", "2.5"}) == "--k expects an integer, got '2.5'");
  CHECK(err({"--max-range", "0"}) == "--max-range must be > 0, or < 0, got 0");
  CHECK(err({"--max-range", "-1"}).empty());
  CHECK(err({"--model", "robust"}) == "--model must be octomap or knn, got 'robust'");
  CHECK(err({"--memory-limit", "1M"}).find("at least 16M") != std::string::npos);
  CHECK(err({"--res", "0.1", "--res", "0.2"}) == "--res given twice");
  CHECK(err({"--res"}) == "--res needs a value");
  CHECK(err({"--res", "--k", "3"}) == "--res needs a value, got the option --k");
  CHECK(err({"--discretize=1"}) == "--discretize takes no value");
  CHECK(err({"--nope"}) == "unknown option --nope (see --help)");
  CHECK(err({"a", "b", "c"}) == "at most 2 files; 'c' is one too many");
}

TEST_CASE("commands: every declared default passes its own check, and help fits 100 columns") {
  std::set<std::string> names;
  for (const cli::Command& c : cli::commands()) {
    const cli::CommandSpec& spec = c.spec();
    CAPTURE(spec.name);
    CHECK(names.insert(spec.name).second);
    CHECK_FALSE(spec.summary.empty());
    std::set<std::string> options;
    for (const cli::OptionGroup& g : spec.groups)
      for (const cli::Option& o : g.options) {
        CAPTURE(o.name());
        CHECK(options.insert(o.name()).second);  // declared once per command
        if (!o.short_form().empty()) CHECK(options.insert(o.short_form()).second);
        if (!o.default_value().empty()) CHECK_NOTHROW(o.check(o.default_value()));
        CHECK_FALSE(o.help().empty());
      }
    std::istringstream help(cli::help_text(spec));
    for (std::string line; std::getline(help, line);) {
      CAPTURE(line);
      CHECK(line.size() <= 100);
    }
  }
  // The Markdown reference names every command and option.
  const std::string md = cli::cli_markdown();
  for (const cli::Command& c : cli::commands()) {
    CHECK(md.find("## knnocc " + c.spec().name + "\n") != std::string::npos);
    for (const cli::OptionGroup& g : c.spec().groups)
      for (const cli::Option& o : g.options) CHECK(md.find(o.name()) != std::string::npos);
  }
}

TEST_CASE("commands: dispatch by name and --scene") {
  REQUIRE(cli::find_command("demo", {}) != nullptr);
  CHECK(cli::find_command("demo", {})->spec().name == "demo");
  CHECK(cli::find_command("demo", {"--scene", "room"})->spec().name == "demo --scene room");
  CHECK(cli::find_command("demo", {"--scene=loop"})->spec().name == "demo --scene loop");
  // An unknown scene reaches the tree demo, whose --scene declaration refuses it.
  CHECK(cli::find_command("demo", {"--scene", "forest"})->spec().name == "demo");
  CHECK(usage_error(cli::demo_spec(), {"--scene", "forest"}) ==
        "--scene must be tree, room or loop, got 'forest'");
  CHECK(cli::find_command("map", {})->spec().name == "map");
  CHECK(cli::find_command("nope", {}) == nullptr);
}

#endif  // KNNOCC_TEST_TOOL_HEADERS
