#pragma once
// knnocc umbrella header: everything except io/, sim/ and eval/ (they read and write files;
// include those one by one).
// Prefer the module headers in your own code: include only what you use.

#include "version.hpp"

#include "core/config.hpp"
#include "core/grid.hpp"
#include "core/key.hpp"
#include "core/log_odds.hpp"
#include "core/point3.hpp"
#include "core/point_traits.hpp"

#include "insertion/scan_inserter.hpp"
#include "map/brick.hpp"
#include "map/occupancy_map.hpp"

#include "raycast/cast_ray.hpp"
#include "raycast/dda.hpp"

#include "sensor/endpoint_rating.hpp"
#include "sensor/knn_model.hpp"
#include "sensor/octomap_model.hpp"

#include "stats/welford.hpp"

#include "knn/affected.hpp"
#include "knn/change_set.hpp"
#include "knn/point_index.hpp"
#include "knn/tracker.hpp"

#include "mapper.hpp"
