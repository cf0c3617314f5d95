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

Option scene_option(const std::string& help) {
  return Option::text("--scene", "NAME", help).one_of({"tree", "room", "loop"});
}

Option demo_res_option() {
  return Option::number("--res", "R", "voxel edge in metres")
      .fallback("0.1")
      .at_least(0.02)
      .at_most(1);
}

Option demo_crop_option() {
  return Option::number("--crop", "M", "keep the points within M of their camera")
      .fallback("4")
      .above(0);
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

OptionGroup knn2022_model_group(const std::string& text) {
  const Knn2022Params p;
  return {"2022 k-NN model (--model knn2022)",
          {Option::integer("--k2022", "K", "neighbours of a point within its keyframe")
               .fallback(std::to_string(p.k))
               .at_least(1)
               .at_most(4096),
           Option::number("--inner-range", "M",
                          "inner points lie within M of their sensor; the other points' rays are "
                          "cut there")
               .fallback(format_number(p.inner_range))
               .above(0)
               .below(1e6),
           Option::number("--p-near", "P", "p_U, probability of a point at d = 0")
               .fallback(format_number(p.p_near))
               .above(0)
               .below(1),
           Option::number("--p-far", "P", "p_W, the limit of p(d) as d grows (< --p-near)")
               .fallback(format_number(p.p_far))
               .above(0)
               .below(1),
           Option::number("--p-miss", "P", "free update of rays to inner points")
               .fallback(format_number(p.p_miss))
               .above(0)
               .below(0.5),
           Option::number("--p-miss-outer", "P",
                          "free update of the other rays, cut at --inner-range (>= --p-miss)")
               .fallback(format_number(p.p_miss_outer))
               .above(0)
               .below(0.5),
           Option::text("--stats", "HOW",
                        "mu and sigma of d: first-pass (over the whole input first, as the "
                        "authors did) or online (running, Welford)")
               .fallback("first-pass")
               .one_of({"first-pass", "online"})},
          text};
}

Knn2022Params knn2022_params(const Args& args, bool& first_pass) {
  Knn2022Params p;
  p.k = static_cast<std::size_t>(args.integer("--k2022"));
  p.inner_range = args.number("--inner-range");
  p.p_near = args.number("--p-near");
  p.p_far = args.number("--p-far");
  p.p_miss = args.number("--p-miss");
  p.p_miss_outer = args.number("--p-miss-outer");
  first_pass = args.str("--stats") == "first-pass";
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("2022 k-NN model: ") + e.what());
  }
  return p;
}

OptionGroup map_output_group() {
  return {"map files",
          {Option::text("--output", "FILE",
                        "a map file in the format its extension names: .bt .ot .ply .png .html "
                        ".yaml (2D grid) .voxels/.txt (voxel list); repeat for several")
               .alias("-o")
               .repeatable(),
           Option::text("--out-bt", "FILE",
                        "OctoMap binary tree (.bt) for octovis / octomap_server: occupied or free "
                        "per voxel, pruned as OctoMap prunes"),
           Option::text("--out-ot", "FILE",
                        "OctoMap full tree (.ot): log-odds per node; a ColorOcTree (r g b per "
                        "node) when the clouds have colour"),
           Option::text("--out-ply", "FILE",
                        "occupied voxel centres as a PLY point cloud (colour = the points' colour "
                        "or height, property logodds) for CloudCompare / MeshLab"),
           Option::flag("--ply-cubes",
                        "a .ply output holds one cube (8 vertices, 6 faces) per "
                        "voxel instead"),
           Option::flag("--ply-free", "a .ply output includes free voxels (light grey)"),
           Option::text("--out-png", "FILE",
                        "a picture: top view (colour = height) above a side view, with legend, "
                        "scale bar and title (zlib-compressed PNG)"),
           Option::text("--out-html", "FILE",
                        "the map in 3D in one self-contained web page, with the sensors' path "
                        "(see knnocc view --help)"),
           Option::text("--out-grid", "FILE.yaml",
                        "a 2D occupancy grid for ROS map_server / Nav2: FILE.yaml and FILE.pgm "
                        "(0 occupied, 254 free, 205 unknown) of the --grid-z band"),
           grid_z_option(),
           Option::flag("--no-color",
                        "ignore the clouds' colours (.ot is then a plain OcTree, .ply and pages "
                        "coloured by height)"),
           up_option("from the sensor poses: camera -y, LiDAR +z; z for map files")},
          ""};
}

Option points_frame_option() {
  return Option::text("--points-frame", "FRAME",
                      "the clouds' frame: sensor (moved into the world with their pose) or world "
                      "(already in world coordinates: moved into the sensor frame with the pose "
                      "first, for --crop, --max-range and the rays)")
      .fallback("sensor")
      .one_of({"sensor", "world"});
}

Option grid_z_option() {
  return Option::text("--grid-z", "MIN:MAX",
                      "the height band of a 2D grid, in metres along up: a cell is occupied when "
                      "a voxel of its column in the band is, free when the column's known voxels "
                      "there are all free, unknown otherwise");
}

OptionGroup octomap_model_group() {
  return {"OctoMap model (--model octomap)",
          {Option::number("--prob-hit", "P", "occupied probability of a hit (setProbHit)")
               .fallback("0.7")
               .above(0.5)
               .below(1),
           Option::number("--prob-miss", "P", "occupied probability of a miss (setProbMiss)")
               .fallback("0.4")
               .above(0)
               .below(0.5),
           Option::text("--clamp", "MIN:MAX",
                        "clamping bounds as probabilities (setClampingThresMin/Max)")
               .fallback("0.1192:0.971")},
          "  OctoMap's .bt/.ot files store none of these (only the tree type, node count and\n"
          "  resolution): a .ot keeps the clamped log-odds, a .bt only occupied or free, and a\n"
          "  reader gives its leaves its own clamping bounds.\n"};
}

}  // namespace knnocc::cli
