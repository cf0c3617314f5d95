#pragma once
// Point3f: knnocc's own plain point (three floats, an aggregate, no alignment demands).
// Ray casting works in float, exactly like OctoMap's point3d, so points of any type are
// converted to Point3f before they are inserted.

namespace knnocc {

struct Point3f {
  float x = 0.0f, y = 0.0f, z = 0.0f;
};

}  // namespace knnocc
