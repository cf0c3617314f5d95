#pragma once
// Options that several commands share, declared once here: the memory limit, threads, the up
// axis, the k-NN model's parameters (map, demo) and the map files a map can be written to (map).

#include <string>

#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>

#include "args.hpp"

namespace knnocc::cli {

/// --memory-limit SIZE: every command that reads or builds a map, or a large cloud, takes it.
Option memory_limit_option();

/// Applies --memory-limit (or the default: 80 % of the machine's memory) to the process and
/// returns it in bytes.
double use_memory_limit(const Args& args);

/// -j, --threads N.
Option threads_option();

/// --up AXIS; `fallback` says where up comes from without it.
Option up_option(const std::string& fallback);

/// The demos' --scene (tree, room, loop), --res (0.02 to 1 m, default 0.1) and --crop (default
/// 4 m, the paper's).
Option scene_option(const std::string& help);
Option demo_res_option();
Option demo_crop_option();

/// The k-NN model's flags (--k --w --p-upper --p-w --p-free --s-limit), defaults from
/// KnnModelParams.
OptionGroup knn_model_group(const std::string& title, const std::string& text);

/// The k-NN model's parameters from its flags; UsageError when they do not fit together.
KnnModelParams knn_params(const Args& args);

/// The 2022 k-NN model's flags (--k2022 --inner-range --p-near --p-far --p-miss --p-miss-outer
/// --stats), defaults from Knn2022Params (map, eval --heldout).
OptionGroup knn2022_model_group(const std::string& text);

/// The 2022 model's parameters from its flags (statistics not yet filled in); UsageError when
/// they do not fit together. `first_pass` says whether --stats asks for the first pass.
Knn2022Params knn2022_params(const Args& args, bool& first_pass);

/// The flags of knn2022_model_group, for commands that refuse them with another model.
inline const char* const kKnn2022Flags[] = {"--k2022",  "--inner-range",  "--p-near", "--p-far",
                                            "--p-miss", "--p-miss-outer", "--stats"};

/// The map files `knnocc map` writes besides --out-voxels (-o, --out-bt ... --no-color), with
/// --up.
OptionGroup map_output_group();

/// --points-frame sensor|world: the frame of the clouds' points (map).
Option points_frame_option();

/// --grid-z MIN:MAX, the height band of a 2D grid (map, convert).
Option grid_z_option();

/// --prob-hit, --prob-miss, --clamp: the OctoMap model's parameters.
OptionGroup octomap_model_group();

}  // namespace knnocc::cli
