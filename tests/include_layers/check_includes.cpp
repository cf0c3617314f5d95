// check_includes: the library's include graph follows its layers (docs/architecture.md).
//
// Every header under include/knnocc belongs to a folder (core, map, raycast, ...; the top-level
// headers to "top"). A header may include headers of its own folder and of the folders its folder
// builds on (kAllowed below), never of a folder above it, so that no include points up and the
// folders form no circle. A folder's internals (X/detail/) are X's: other folders include them only
// where kAllowed names them (core/detail, the shared machinery, is open to all). Files must not
// include each other in a circle either. The library includes itself by relative quoted paths only.
// The umbrella header knnocc.hpp includes every header but io/, eval/, sim/, tiles/ and detail/
// ones.
//
// usage: check_includes INCLUDE_DIR    (prints every violation; exit status 1 if there is one)

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// What each folder may include besides itself, its own detail/ and core/detail/.
const std::map<std::string, std::set<std::string>> kAllowed = {
    {"core", {}},
    {"stats", {}},
    {"map", {"core"}},
    {"raycast", {"core", "map"}},
    {"knn", {"core", "stats"}},
    // A contextual model (sensor/contextual_model.hpp) keeps per-map-point state against the map:
    // it reads and updates voxels and walks rays for free-space evidence (the robust model's
    // see-through counts on the dense walks of raycast/detail).
    {"sensor", {"core", "stats", "knn", "map", "raycast", "raycast/detail"}},
    // map/detail/brick_access.hpp: whole-brick writers and readers (apply, tree files, replay).
    {"insertion", {"core", "map", "map/detail", "raycast", "raycast/detail", "sensor"}},
    {"top", {"core", "stats", "map", "raycast", "knn", "sensor", "insertion"}},
    // The live mapper composes Mapper (top) and replays regions of its map.
    {"live", {"top", "core", "map", "map/detail", "knn"}},
    // knnocc.hpp, the umbrella: every layer but io, eval and sim.
    {"umbrella", {"core", "stats", "map", "raycast", "knn", "sensor", "insertion", "top", "live"}},
    {"io", {"core", "map", "map/detail"}},
    {"eval", {"core", "map", "raycast", "io", "io/detail"}},  // raycast: held-out rays
    {"sim", {"core", "eval", "io"}},
    // Tiles of a larger map: the rating pass composes Mapper (top); tiles are integrated with the
    // clipped inserters and written and merged as OctoMap files.
    {"tiles",
     {"top", "core", "map", "map/detail", "raycast", "insertion", "sensor", "knn", "io",
      "io/detail"}},
};

// "map" for include/knnocc/map/x.hpp, "map/detail" for include/knnocc/map/detail/x.hpp, "top" for
// include/knnocc/x.hpp.
std::string area(const fs::path& rel) {
  std::vector<std::string> parts;
  for (const auto& p : rel) parts.push_back(p.string());
  if (parts.size() == 1) return parts[0] == "knnocc.hpp" ? "umbrella" : "top";
  if (parts.size() > 2 && parts[1] == "detail") return parts[0] + "/detail";
  return parts[0];
}
std::string folder_of(const std::string& a) { return a.substr(0, a.find('/')); }

bool may_include(const std::string& from, const std::string& to) {
  const std::string owner = folder_of(from);
  if (folder_of(to) == owner || to == "core/detail") return true;
  const auto it = kAllowed.find(owner);
  return it != kAllowed.end() && it->second.count(to) > 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: check_includes INCLUDE_DIR\n");
    return 2;
  }
  const fs::path root = fs::path(argv[1]) / "knnocc";
  const std::regex quoted(R"re(^\s*#\s*include\s*"([^"]+)")re");
  const std::regex angled(R"re(^\s*#\s*include\s*<knnocc/)re");
  std::map<fs::path, std::vector<fs::path>> graph;
  int problems = 0;
  auto report = [&](const std::string& what) {
    std::printf("%s\n", what.c_str());
    ++problems;
  };
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".hpp") continue;
    const fs::path file = entry.path().lexically_normal();
    const fs::path rel = file.lexically_relative(root);
    const std::string from = area(rel);
    if (!kAllowed.count(folder_of(from)))
      report(rel.string() + ": folder '" + folder_of(from) + "' has no place in the layers");
    graph[file];
    std::ifstream in(file);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      const std::string where = rel.string() + ":" + std::to_string(n) + ": ";
      if (std::regex_search(line, angled)) report(where + "includes the library by <knnocc/...>");
      std::smatch m;
      if (!std::regex_search(line, m, quoted)) continue;
      const fs::path target = (file.parent_path() / m[1].str()).lexically_normal();
      const fs::path target_rel = target.lexically_relative(root);
      if (target_rel.empty() || *target_rel.begin() == "..") {
        report(where + "includes " + m[1].str() + ", outside the library");
        continue;
      }
      if (!fs::exists(target)) {
        report(where + "includes " + m[1].str() + ", which does not exist");
        continue;
      }
      graph[file].push_back(target);
      const std::string to = area(target_rel);
      if (!may_include(from, to))
        report(where + from + " may not include " + to + " (" + target_rel.string() + ")");
    }
  }
  // Circles between files: depth-first search, grey = on the current path.
  std::map<fs::path, int> colour;  // 0 white, 1 grey, 2 black
  std::vector<fs::path> path;
  std::function<void(const fs::path&)> visit = [&](const fs::path& f) {
    colour[f] = 1;
    path.push_back(f);
    for (const fs::path& g : graph[f]) {
      if (colour[g] == 1) {
        std::string circle;
        bool on = false;
        for (const fs::path& p : path) {
          on = on || p == g;
          if (on) circle += p.lexically_relative(root).string() + " -> ";
        }
        report("circle: " + circle + g.lexically_relative(root).string());
      } else if (colour[g] == 0) {
        visit(g);
      }
    }
    path.pop_back();
    colour[f] = 2;
  };
  for (const auto& [f, targets] : graph)
    if (colour[f] == 0) visit(f);
  // The umbrella header includes every public header but those of io/, eval/, sim/ and tiles/
  // (which need Eigen and read files) and the folders' internals.
  const fs::path umbrella = (root / "knnocc.hpp").lexically_normal();
  const auto& direct = graph[umbrella];
  for (const auto& [f, targets] : graph) {
    const fs::path rel = f.lexically_relative(root);
    const std::string a = area(rel);
    const std::string folder = folder_of(a);
    if (f == umbrella || a.find("/detail") != std::string::npos || folder == "io" ||
        folder == "eval" || folder == "sim" || folder == "tiles")
      continue;
    if (std::find(direct.begin(), direct.end(), f) == direct.end())
      report("knnocc.hpp does not include " + rel.string());
  }
  std::printf("%zu headers checked, %d problem(s)\n", graph.size(), problems);
  return problems ? 1 : 0;
}
