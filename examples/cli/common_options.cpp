#include "common_options.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>

#include "resource_limits.hpp"

namespace knnocc::cli {

Option memory_limit_option() {
  return Option::size("--memory-limit", "SIZE",
                      "the most memory the command may take, e.g. 800M or 4G; a map may use 75 % "
                      "of it. Work that surely needs more is refused before it starts; running "
                      "out later is one line naming the file (exit 2)")
      .fallback_text("80 % of the machine's memory, or of a lower address-space or cgroup limit");
}

double use_memory_limit(const Args& args) {
  const double bytes = args.size("--memory-limit", default_memory_limit());
  apply_memory_limit(bytes);
  return bytes;
}

Option threads_option() {
  return Option::integer("--threads", "N",
                         "threads that walk the rays of each cloud; the map is the same for every "
                         "N; more than the machine's hardware threads are capped, with a note")
      .alias("-j")
      .fallback("1")
      .at_least(1)
      .at_most(1024);
}

Option up_option(const std::string& fallback) {
  return Option::text("--up", "AXIS", "which way is up in pictures and pages")
      .one_of({"x", "y", "z", "-x", "-y", "-z"})
      .fallback_text(fallback);
}

OptionGroup knn_model_group(const std::string& title, const std::string& text) {
  const KnnModelParams p;
  return {title,
          {Option::integer("--k", "K", "neighbours per map point")
               .alias("-k")
               .fallback(std::to_string(p.k))
               .at_least(1)
               .at_most(4096),
           Option::number("--w", "W", "reliability threshold in sigmas above mu")
               .fallback(format_number(p.w))
               .at_least(-8)
               .at_most(8),
           Option::number("--p-upper", "P", "P_u, probability of the most reliable endpoints")
               .fallback(format_number(p.p_upper))
               .above(0.5)
               .below(1),
           Option::number("--p-w", "P", "P_w, probability at s = mu + w sigma (P_w < P_u)")
               .fallback(format_number(p.p_w))
               .above(0.5)
               .below(1),
           Option::number("--p-free", "P", "free-ray probability (OctoMap's miss)")
               .fallback(format_number(p.p_free))
               .above(0)
               .below(0.5),
           Option::number("--s-limit", "X", "valid map points have s_p < X")
               .fallback_text("no limit")
               .above(0)},
          text};
}

KnnModelParams knn_params(const Args& args) {
  KnnModelParams p;
  p.k = static_cast<std::size_t>(args.integer("--k"));
  p.w = args.number("--w");
  p.p_upper = args.number("--p-upper");
  p.p_w = args.number("--p-w");
  p.p_free = args.number("--p-free");
  p.s_limit = args.number("--s-limit", p.s_limit);
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("k-NN model: ") + e.what());
  }
  return p;
}

OptionGroup map_output_group() {
  return {"map files",
          {Option::text("--out-bt", "FILE",
                        "OctoMap binary tree (.bt) for octovis / octomap_server: occupied or free "
                        "per voxel, pruned as OctoMap prunes"),
           Option::text("--out-ot", "FILE", "OctoMap full tree (.ot): log-odds per node"),
           Option::text("--out-ply", "FILE",
                        "occupied voxel centres as a PLY point cloud (colour = height, property "
                        "logodds) for CloudCompare / MeshLab"),
           Option::flag("--ply-cubes",
                        "--out-ply writes one cube (8 vertices, 6 faces) per voxel instead"),
           Option::flag("--ply-free", "--out-ply includes free voxels (light grey)"),
           Option::text("--out-png", "FILE",
                        "a picture: top view (colour = height) above a side view, with legend, "
                        "scale bar and title (zlib-compressed PNG)"),
           Option::text("--out-html", "FILE",
                        "the map in 3D in one self-contained web page (see knnocc view --help)"),
           up_option("from the sensor poses: camera -y, LiDAR +z; z for map files")},
          ""};
}

}  // namespace knnocc::cli
