#pragma once
// knnocc umbrella header: everything except io/ (include those readers and writers one by one).
// Prefer the module headers in your own code: include only what you use.

#include "version.hpp"

#include "core/config.hpp"
#include "core/grid.hpp"
#include "core/key.hpp"
#include "core/log_odds.hpp"
#include "core/point3.hpp"
#include "core/point_traits.hpp"

#include "map/brick.hpp"
#include "map/occupancy_map.hpp"
#include "map/scan_inserter.hpp"

#include "raycast/cast_ray.hpp"
#include "raycast/dda.hpp"

#include "sensor/octomap_model.hpp"
