#pragma once
// Options that several commands share, declared once here: the memory limit, threads, the up
// axis, the k-NN model's parameters (map, demo) and the map files a map can be written to (map).

#include <string>

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

/// The k-NN model's flags (--k --w --p-upper --p-w --p-free --s-limit), defaults from
/// KnnModelParams.
OptionGroup knn_model_group(const std::string& title, const std::string& text);

/// The k-NN model's parameters from its flags; UsageError when they do not fit together.
KnnModelParams knn_params(const Args& args);

/// The map files `knnocc map` writes besides --out-voxels (--out-bt ... --ply-free), with --up.
OptionGroup map_output_group();

}  // namespace knnocc::cli
