// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// EndpointRating: what a per-endpoint sensor model (KnnModel) says about one endpoint of a scan;
// ScanInserter::insert_rated applies a scan of them.

namespace knnocc {

struct EndpointRating {
  float logodds = 0.0f;    ///< occupied update of the endpoint's voxel (summed per voxel, eq 15)
  bool casts_ray = false;  ///< the voxels from the sensor to the endpoint get the free update
};

}  // namespace knnocc
