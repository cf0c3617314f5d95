// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// knnocc umbrella header: every public header but those of io/, eval/, sim/ and tiles/ (they read
// and write files and need Eigen: include those one by one). tests/include_layers checks that this
// list is complete.
// Prefer the module headers in your own code: include only what you use.

#include "version.hpp"

#include "core/config.hpp"
#include "core/grid.hpp"
#include "core/key.hpp"
#include "core/log_odds.hpp"
#include "core/memory_limit.hpp"
#include "core/point3.hpp"
#include "core/point_evidence.hpp"
#include "core/point_traits.hpp"
#include "core/rgb.hpp"

#include "stats/welford.hpp"

#include "map/brick.hpp"
#include "map/occupancy_grid_2d.hpp"
#include "map/occupancy_map.hpp"
#include "map/same_voxels.hpp"
#include "map/value_pool.hpp"

#include "raycast/cast_ray.hpp"
#include "raycast/dda.hpp"

#include "knn/affected.hpp"
#include "knn/ball_grid.hpp"
#include "knn/change_set.hpp"
#include "knn/nanoflann_compat.hpp"
#include "knn/point_index.hpp"
#include "knn/tracker.hpp"
#include "knn/tracker_concept.hpp"
#include "knn/tracker_types.hpp"

#include "sensor/cloud_model.hpp"
#include "sensor/contextual_model.hpp"
#include "sensor/endpoint_rating.hpp"
#include "sensor/knn2022_model.hpp"
#include "sensor/knn_model.hpp"
#include "sensor/layered_rating.hpp"
#include "sensor/map_point_ledger.hpp"
#include "sensor/octomap_model.hpp"
#include "sensor/rated_keyframe.hpp"
#include "sensor/real_point_mixture.hpp"
#include "sensor/robust_model.hpp"
#include "sensor/sensor_model.hpp"
#include "sensor/voxel_tally.hpp"

#include "insertion/layered_scan_inserter.hpp"
#include "insertion/scan_inserter.hpp"
#include "insertion/scan_integrator.hpp"
#include "insertion/scan_stats.hpp"
#include "insertion/voxel_colors.hpp"

#include "mapper.hpp"

#include "live/keyframe_store.hpp"
#include "live/live_mapper.hpp"
#include "live/rigid_pose.hpp"
