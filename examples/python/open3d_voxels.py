#!/usr/bin/env python3
"""A knnocc map's occupied voxels as an Open3D VoxelGrid.

    PYTHONPATH=build/python python3 examples/python/open3d_voxels.py voxels.ply

maps a simulated room scan at 0.05 m, turns the occupied voxel centres into an
open3d.geometry.VoxelGrid with the map's voxel size (the grid's origin on a voxel corner, so each
centre fills one voxel, coloured by height), checks that, and writes the grid as a PLY. Needs
Open3D (Debian: python3-open3d); without it the example says so and does nothing.
"""

import sys

import numpy as np

import knnocc

try:
    import open3d as o3d
except ImportError:
    print("KNNOCC_SKIPPED: open3d is not installed (Debian: python3-open3d)")
    sys.exit(0)


def room_scan(n=60000, seed=1):
    """A sensor at the origin of a 6 x 4 x 2.5 m room (floor z = -1): points on its walls."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    half = np.array([3.0, 2.0, 1.25])
    centre = np.array([0.0, 0.0, 0.25])
    t = np.min(np.abs((half * np.sign(d) + centre) / d), axis=1)  # first wall along d
    return (d * t[:, None]).astype(np.float32)


def main(out):
    m = knnocc.OccupancyMap(0.05)
    m.insert_point_cloud(room_scan(), origin=(0, 0, 0))
    occupied, _ = m.extract_point_cloud()
    z = occupied[:, 2]
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(occupied))
    colours = np.stack([(z - z.min()) / np.ptp(z), 0.3 * np.ones_like(z), 1 - (z - z.min()) / np.ptp(z)], 1)
    cloud.colors = o3d.utility.Vector3dVector(colours)
    half = m.resolution / 2
    grid = o3d.geometry.VoxelGrid.create_from_point_cloud_within_bounds(
        cloud, m.resolution, occupied.min(0) - half, occupied.max(0) + half)
    assert len(grid.get_voxels()) == len(occupied), (len(grid.get_voxels()), len(occupied))
    o3d.io.write_voxel_grid(out, grid)
    print(f"occupied {len(occupied)} voxel_grid {len(grid.get_voxels())} voxel_size {grid.voxel_size}")
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
