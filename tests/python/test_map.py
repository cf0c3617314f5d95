"""OccupancyMap, Mapper and LiveMapper without the tool: OctoMap's semantics on cases with a known
answer, queries that agree with the map's own voxels, a dense-sampling oracle for cast_ray, file,
byte and pickle round trips, inputs read in place, and the live mapper's invariant."""

import pickle

import numpy as np
import pytest

from conftest import random_scan

HIT = np.float32(np.log(0.7 / 0.3))  # OctoMap's l_occ, rounded to float as liboctomap does
MISS = np.float32(np.log(0.4 / 0.6))


def test_one_ray_along_an_axis(knnocc):
    m = knnocc.OccupancyMap(0.1)
    m.insert_point_cloud(np.array([[1.05, 0.05, 0.05]], np.float32), origin=(0.05, 0.05, 0.05))
    # The ray frees the 10 voxels from the origin's to the end point's, which is occupied.
    free = np.array([[0.05 + 0.1 * i, 0.05, 0.05] for i in range(10)])
    assert list(m.occupancy_at(free)) == [0] * 10
    assert m.occupancy_at([1.05, 0.05, 0.05]) == 1
    assert m.logodds_at([[1.05, 0.05, 0.05]])[0] == HIT
    assert np.all(m.logodds_at(free) == MISS)
    assert m.occupancy_at([[0.05, 0.15, 0.05], [1e6, 0, 0]]).tolist() == [-1, -1]
    assert np.isnan(m.logodds_at([[0.05, 0.15, 0.05]])[0])
    assert len(m) == 11 and m.count_voxels() == (1, 10)
    assert m.resolution == 0.1


def test_queries_agree_with_the_voxels(knnocc):
    m = knnocc.OccupancyMap(0.05)
    for seed in range(3):
        m.insert_point_cloud(random_scan(seed), origin=(0.1 * seed, 0, 0))
    centres, logodds = m.voxels("all")
    assert centres.shape == (len(m), 3) and centres.dtype == np.float64
    assert logodds.dtype == np.float32
    assert np.array_equal(m.logodds_at(centres), logodds)
    assert np.array_equal(m.occupancy_at(centres), (logodds >= 0).astype(np.int8))
    occupied, free = m.extract_point_cloud()
    assert (len(occupied), len(free)) == m.count_voxels()
    assert np.array_equal(m.voxels("occupied")[0], occupied)
    assert np.array_equal(m.voxels("free")[0], free)
    assert np.all(m.occupancy_at(occupied) == 1) and np.all(m.occupancy_at(free) == 0)
    # Any (..., 3) shape: one result per point.
    assert m.occupancy_at(centres[:12].reshape(2, 2, 3, 3)).shape == (2, 2, 3)


def test_float32_float64_threads_and_mapper_give_one_map(knnocc):
    scans = [random_scan(s) for s in range(4)]
    origins = [(0, 0, 0), (0.3, 0.1, 0), (0.6, -0.2, 0.1), (0, 0.5, 0)]
    maps = [knnocc.OccupancyMap(0.05) for _ in range(3)]
    mapper = knnocc.Mapper(0.05)
    for scan, origin in zip(scans, origins):
        maps[0].insert_point_cloud(scan, origin)
        maps[1].insert_point_cloud(scan.astype(np.float64), origin)
        maps[2].insert_point_cloud(scan, origin, threads=2)
        mapper.insert_keyframe(origin, scan)
    assert maps[0] == maps[1] == maps[2] == mapper.map
    assert maps[0].to_bytes("ot") == mapper.map.to_bytes("ot")


def test_max_range_and_discretize(knnocc):
    scan = random_scan(7)
    a, b = knnocc.OccupancyMap(0.1), knnocc.OccupancyMap(0.1)
    a.insert_point_cloud(scan, (0, 0, 0), max_range=2.0)
    b.insert_point_cloud(scan, (0, 0, 0))
    occupied, _ = a.extract_point_cloud()
    assert np.all(np.linalg.norm(occupied, axis=1) < 2.0 + 0.1)  # nothing occupied far away
    assert a.count_voxels()[0] < b.count_voxels()[0]
    c = knnocc.OccupancyMap(0.1)
    c.insert_point_cloud(scan, (0, 0, 0), discretize=True)
    assert c.count_voxels()[0] == b.count_voxels()[0]  # the same endpoint voxels


def test_files_bytes_and_pickle(knnocc, tmp_path):
    m = knnocc.OccupancyMap(0.05, prob_hit=0.8, prob_miss=0.3, clamp_min=0.12, clamp_max=0.97)
    m.insert_point_cloud(random_scan(1), (0, 0, 0))
    m.write(tmp_path / "m.bt")
    m.write(str(tmp_path / "m.ot"))
    assert (tmp_path / "m.bt").read_bytes() == m.to_bytes("bt") == m.to_bytes()
    assert (tmp_path / "m.ot").read_bytes() == m.to_bytes("ot")
    assert knnocc.read_map(tmp_path / "m.ot").to_bytes("ot") == m.to_bytes("ot")
    bt = knnocc.read_map(tmp_path / "m.bt")  # occupied/free only: the clamping bounds
    assert bt.to_bytes("bt") == m.to_bytes("bt")
    assert bt.count_voxels() == m.count_voxels()

    copy = pickle.loads(pickle.dumps(m))
    assert copy == m and copy.to_bytes("ot") == m.to_bytes("ot")
    # The copy keeps the model and the clamping: the same next scan gives the same map again.
    for x in (m, copy):
        x.insert_point_cloud(random_scan(2), (0.2, 0, 0))
    assert copy == m
    # A Mapper's map pickles to a map of its own.
    mapper = knnocc.Mapper(0.1)
    mapper.insert_keyframe((0, 0, 0), random_scan(3))
    assert pickle.loads(pickle.dumps(mapper.map)) == mapper.map
    assert knnocc.OccupancyMap(0.1) != mapper.map


def _first_stop(m, origin, direction, max_range):
    """The dense-sampling oracle: the voxel centre where a walk from `origin` along `direction`
    stops with ignore_unknown (the first occupied voxel), sampled every 1e-4 of a voxel."""
    d = np.asarray(direction, np.float64) / np.linalg.norm(direction)
    t = np.arange(0.0, max_range, m.resolution * 1e-4)
    samples = np.asarray(origin) + t[:, None] * d
    occ = np.nonzero(m.occupancy_at(samples) == 1)[0]
    if len(occ) == 0:
        return None
    return (np.floor(samples[occ[0]] / m.resolution) + 0.5) * m.resolution


def test_cast_ray_against_dense_sampling(knnocc):
    m = knnocc.OccupancyMap(0.1)
    m.insert_point_cloud(random_scan(5, n=5000), (0, 0, 0))
    rng = np.random.default_rng(11)
    origins = np.tile([0.02, 0.03, 0.01], (40, 1))
    directions = rng.normal(size=(40, 3))
    hits, ends = m.cast_ray(origins, directions, max_range=6.0, ignore_unknown=True)
    assert hits.shape == (40,) and ends.shape == (40, 3)
    for i in range(40):
        expect = _first_stop(m, origins[i], directions[i], 6.0)
        assert hits[i] == (expect is not None)
        if expect is not None:
            assert np.allclose(ends[i], expect, atol=1e-9)
        one_hit, one_end = knnocc.cast_ray(m, origins[i], directions[i], 6.0, True)
        assert one_hit == hits[i] and np.array_equal(one_end, ends[i])
    # Without ignore_unknown the walk stops at the first unknown voxel, which is no hit.
    hit, end = m.cast_ray((0.02, 0.03, 0.01), (0, 0, 1))
    assert not hit and m.occupancy_at(end) == -1


def test_inputs_are_read_in_place(knnocc):
    m = knnocc.OccupancyMap(0.1)
    for dtype in (np.float32, np.float64):
        points = np.ascontiguousarray(random_scan(0, n=1000), dtype=dtype)
        m.insert_point_cloud(points, (0, 0, 0))
        assert knnocc._last_points_input() == (points.ctypes.data, False)
        m.occupancy_at(points)
        assert knnocc._last_points_input() == (points.ctypes.data, False)
        view = points[10:20]  # a C-contiguous view: still the caller's memory
        m.logodds_at(view)
        assert knnocc._last_points_input() == (view.ctypes.data, False)
    # Anything else is converted once, with the same result.
    points = random_scan(0, n=1000)
    expect = m.occupancy_at(points)
    others = [(np.asfortranarray(points), expect), (points[::2], expect[::2]),
              (np.concatenate([points, points], axis=1)[:, :3], expect),
              (points.tolist(), expect), (points.astype(np.float16), None)]
    for other, same in others:
        result = m.occupancy_at(other)
        address, converted = knnocc._last_points_input()
        assert converted and address != points.ctypes.data
        assert same is None or np.array_equal(result, same)


def test_live_mapper_equals_a_mapper_over_its_keyframes(knnocc):
    rng = np.random.default_rng(4)

    def pose(yaw, x, y):
        c, s = np.cos(yaw), np.sin(yaw)
        return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, 0.2], [0, 0, 0, 1]])

    clouds = [random_scan(10 + i, n=400, extent=2.0) for i in range(8)]
    ids = [rng.choice(1500, size=400, replace=False) for _ in range(8)]
    poses = {i: pose(0.1 * i, 0.2 * i, 0.05 * i) for i in range(8)}
    for model in ("octomap", "knn"):
        live = knnocc.LiveMapper(0.1, model=model, k=5) if model == "knn" else \
            knnocc.LiveMapper(0.1)
        for i in range(8):
            live.add(i, poses[i], clouds[i], ids[i])
        moved = {3: pose(0.35, 0.7, 0.1), 6: pose(0.5, 1.1, 0.4)}
        live.repose(moved)
        poses.update(moved)
        live.remove([1, 4])
        assert len(live) == 6 and 3 in live and 1 not in live and -1 not in live
        assert live.last_update["changed"] == 2
        scratch = knnocc.Mapper(0.1, model=model, k=5) if model == "knn" else knnocc.Mapper(0.1)
        for i in (0, 2, 3, 5, 6, 7):
            scratch.insert_keyframe(poses[i][:3, 3], knnocc.to_world(poses[i], clouds[i]), ids[i])
        assert live.map == scratch.map
        assert live.statistics() == scratch.statistics()
        poses = {i: pose(0.1 * i, 0.2 * i, 0.05 * i) for i in range(8)}


def test_to_world_matches_the_pose(knnocc):
    pose = np.eye(4)
    pose[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    pose[:3, 3] = [1, 2, 3]
    points = np.array([[1, 0, 0], [0, 1, 0]], np.float32)
    assert np.array_equal(knnocc.to_world(pose, points), [[1, 3, 3], [0, 2, 3]])
