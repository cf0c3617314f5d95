// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Point3f / Point3d: knnocc's own plain points (aggregates, no alignment demands).
// Ray casting works in float, exactly like OctoMap's point3d, so points of any type are
// converted to Point3f before they are inserted; the k-NN tracker keeps map points in double.

namespace knnocc {

struct Point3f {
  float x = 0.0f, y = 0.0f, z = 0.0f;
};

struct Point3d {
  double x = 0.0, y = 0.0, z = 0.0;
};

}  // namespace knnocc
