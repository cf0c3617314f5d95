#!/usr/bin/env python3
"""ORB-SLAM keyframes to an OctoMap .bt and a picture, with knnocc's robust model.

    PYTHONPATH=build/python python3 examples/python/orbslam_map.py \\
        ../shared/data/orbslam2_stereo_keyframes out/orbslam

reads the keyframes (camera-frame clouds whose points carry ORB-SLAM map-point ids,
camera-to-world poses), keeps the points within 4 m of their camera, maps them at 0.1 m and
writes out/orbslam.bt (octovis opens it) and out/orbslam.png, a top view: occupied voxels
coloured by height (purple low, yellow high) over the free space in grey. The picture is written by the small PNG writer
below (numpy and zlib, no plotting library). The map is the one
`knnocc map --input ... --model robust --crop 4 --res 0.1 --out-bt ...` writes.
"""

import os
import struct
import sys
import time
import zlib

import numpy as np

import knnocc


def crop(points, ids, max_distance):
    """Points within max_distance of the camera (the tool's --crop)."""
    p = points.astype(np.float64)
    keep = np.sqrt(p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1] + p[:, 2] * p[:, 2]) <= max_distance
    return points[keep], None if ids is None else ids[keep]


def write_png(path, rgb):
    """An 8-bit RGB image (H, W, 3) as a PNG file."""
    h, w, _ = rgb.shape
    rows = np.concatenate([np.zeros((h, 1), np.uint8), rgb.reshape(h, 3 * w)], axis=1)

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows.tobytes(), 9)) + chunk(b"IEND", b""))


def top_view(m, pixels_per_voxel=4):
    """The map seen from above (ORB-SLAM's world: y points down): the highest occupied voxel of
    each column coloured from purple (low) over green to yellow (high), known-free columns grey."""
    occupied, free = m.extract_point_cloud()
    r = m.resolution
    lo = np.floor(np.minimum(occupied.min(0), free.min(0)) / r)
    cells = lambda c: (np.floor(c / r) - lo).astype(int)  # noqa: E731
    o, f = cells(occupied), cells(free)
    w, h = max(o[:, 0].max(), f[:, 0].max()) + 1, max(o[:, 2].max(), f[:, 2].max()) + 1
    img = np.full((h, w, 3), 255, np.uint8)
    img[h - 1 - f[:, 2], f[:, 0]] = 200
    height = -occupied[:, 1]
    top = np.full((h, w), -np.inf)
    np.maximum.at(top, (h - 1 - o[:, 2], o[:, 0]), height)
    seen = np.isfinite(top)
    low, high = np.percentile(height, [2, 98])  # a few stray voxels do not set the scale
    t = np.clip((top[seen] - low) / max(high - low, 1e-9), 0, 1)
    stops = np.array([[68, 1, 84], [33, 145, 140], [253, 231, 37]], float)  # viridis' ends, middle
    img[seen] = np.stack([np.interp(t, [0, 0.5, 1], stops[:, c]) for c in range(3)], 1)
    return np.kron(img, np.ones((pixels_per_voxel, pixels_per_voxel, 1), np.uint8))


def main(folder, out):
    if not os.path.isdir(folder):
        print(f"KNNOCC_SKIPPED: no ORB-SLAM keyframes at {folder}")
        return
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    start = time.perf_counter()
    mapper = knnocc.Mapper(0.1, model="robust")
    keyframes = knnocc.read_sequence(folder)
    for pose, points, ids in keyframes:
        points, ids = crop(points, ids, 4.0)
        mapper.insert_keyframe(pose[:3, 3], knnocc.to_world(pose, points), ids)
    occupied, free = mapper.map.count_voxels()
    print(f"keyframes {len(keyframes)} occupied {occupied} free {free} "
          f"seconds {time.perf_counter() - start:.3f}")
    mapper.map.write(out + ".bt")
    write_png(out + ".png", top_view(mapper.map))
    print(f"wrote {out}.bt, {out}.png")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
