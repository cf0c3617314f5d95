"""Every error path of the module: bad arguments and shapes raise ValueError (wrong types
TypeError), unreadable or malformed files knnocc.Error (an OSError naming the file), the memory
limit MemoryError; the object stays usable after each."""

import numpy as np
import pytest

from conftest import random_scan

POINTS = np.zeros((4, 3), np.float32) + 1


@pytest.mark.parametrize("args", [
    (0.0,), (-1.0,), (float("nan"),), (float("inf"),), (1e-9,),
    (0.1, 0.5), (0.1, 1.0), (0.1, 0.7, 0.5), (0.1, 0.7, 0.0),
    (0.1, 0.7, 0.4, 0.0), (0.1, 0.7, 0.4, 0.6), (0.1, 0.7, 0.4, 0.1192, 0.4),
    (0.1, 0.7, 0.4, 0.1192, 1.0),
])
def test_bad_map_parameters(knnocc, args):
    with pytest.raises(ValueError):
        knnocc.OccupancyMap(*args)


def test_wrong_types(knnocc):
    with pytest.raises(TypeError):
        knnocc.OccupancyMap("0.1")
    with pytest.raises(TypeError):
        knnocc.Mapper(0.1, model="knn", k=2.5)
    with pytest.raises(TypeError):
        knnocc.Mapper(0.1, max_range="far")
    with pytest.raises(TypeError):
        knnocc.Mapper(0.1, discretize="yes")
    with pytest.raises(TypeError):
        knnocc.LiveMapper(0.1).add("one", np.eye(4), POINTS)


@pytest.mark.parametrize("points", [
    np.zeros((5, 2)), np.zeros(2), np.zeros((2, 4), np.float32), np.float64(1.0),
    [["a", "b", "c"]], [[1, 2], [3, 4]], None,
])
def test_bad_point_shapes(knnocc, points):
    m = knnocc.OccupancyMap(0.1)
    for call in (lambda: m.insert_point_cloud(points, (0, 0, 0)), lambda: m.occupancy_at(points),
                 lambda: m.logodds_at(points), lambda: knnocc.to_world(np.eye(4), points),
                 lambda: knnocc.Mapper(0.1).insert_keyframe((0, 0, 0), points)):
        with pytest.raises(ValueError, match="points"):
            call()
    assert len(m) == 0


def test_bad_insertion_arguments(knnocc):
    m = knnocc.OccupancyMap(0.1)
    for origin in [(0, 0), (0, 0, 0, 0), (0, float("nan"), 0), "abc"]:
        with pytest.raises(ValueError, match="origin"):
            m.insert_point_cloud(POINTS, origin)
    with pytest.raises(ValueError, match="max_range"):
        m.insert_point_cloud(POINTS, (0, 0, 0), max_range=0.0)
    with pytest.raises(ValueError, match="threads"):
        m.insert_point_cloud(POINTS, (0, 0, 0), threads=0)
    with pytest.raises(ValueError):
        m.voxels("some")
    with pytest.raises(ValueError):
        m.to_bytes("png")
    with pytest.raises(ValueError, match=r"\.bt or \.ot"):
        m.write("map.png")
    with pytest.raises(ValueError, match="ray 0"):
        m.cast_ray((0, 0, 0), (0, 0, 0))
    with pytest.raises(ValueError, match="ray 1"):
        m.cast_ray([[0, 0, 0], [1e9, 0, 0]], (1, 0, 0))
    with pytest.raises(ValueError, match="origins"):
        m.cast_ray(np.zeros((2, 3)), np.ones((3, 3)))
    m.insert_point_cloud(POINTS, (0, 0, 0))  # still usable
    assert len(m) > 0


def test_bad_mapper_arguments(knnocc):
    for model, params in [("octo", {}), ("octomap", {"k": 5}), ("knn", {"prob_hit": 0.7}),
                          ("knn", {"margin_scale": 2}), ("knn", {"k": 0}), ("knn", {"k": 5000}),
                          ("knn", {"p_w": 0.5}), ("knn", {"w": 9}), ("robust", {"margin_scale": -1}),
                          ("octomap", {"threads": 0}), ("octomap", {"max_range": 0}),
                          ("octomap", {"clamp_min": 0.6}), ("knn", {"discretize": True}),
                          ("knn2022", {"w": 0}), ("knn2022", {"margin_scale": 2}),
                          ("knn2022", {"k": 0}), ("knn2022", {"p_near": 0.3}),
                          ("knn2022", {"p_miss": 0.5}), ("knn2022", {"mu": -1, "sigma": 1}),
                          ("knn", {"inner_range": 4})]:
        with pytest.raises(ValueError):
            knnocc.Mapper(0.1, model=model, **params)
    with pytest.raises(ValueError, match="mu and sigma go together"):
        knnocc.Mapper(0.1, model="knn2022", mu=0.1)
    for model in ["robust", "knn2022"]:
        with pytest.raises(ValueError, match="robust"):
            knnocc.LiveMapper(0.1, model=model)
    for k, inner_range in [(0, 4.0), (5000, 4.0), (24, 0.0)]:
        with pytest.raises(ValueError):
            knnocc.Knn2022FirstPass(k, inner_range)
    mapper = knnocc.Mapper(0.1, model="knn")
    for ids in [np.arange(3), np.arange(4.0), [-1, 0, 1, 2], np.zeros((4, 1), int), "abcd"]:
        with pytest.raises(ValueError, match="ids"):
            mapper.insert_keyframe((0, 0, 0), POINTS, ids)
    with pytest.raises(ValueError, match="reserved"):
        mapper.insert_keyframe((0, 0, 0), POINTS, np.full(4, 2**64 - 1, np.uint64))
    for evidence in [np.ones((4, 2), int), np.ones((3, 3), int), np.full((4, 3), -1),
                     np.full((4, 3), 2**32), np.ones((4, 3)), "abcd"]:
        with pytest.raises(ValueError, match="evidence"):
            mapper.insert_keyframe((0, 0, 0), POINTS, np.arange(4), evidence=evidence)
    mapper.insert_keyframe((0, 0, 0), POINTS, np.arange(4))
    with pytest.raises(ValueError, match="mixed"):  # a sequence gives ids always or never
        mapper.insert_keyframe((0, 0, 0), POINTS)
    with pytest.raises(ValueError, match="read-only"):
        mapper.map.insert_point_cloud(POINTS, (0, 0, 0))
    with pytest.raises(ValueError, match="read-only"):
        mapper.map.memory_limit = 1000


def test_bad_live_mapper_arguments(knnocc):
    live = knnocc.LiveMapper(0.1)
    live.add(0, np.eye(4), POINTS)
    bad_poses = [np.eye(3), np.zeros((4, 4)), np.diag([2.0, 1, 1, 1]), np.diag([1.0, 1, -1, 1]),
                 np.where(np.eye(4) == 1, np.nan, 0.0), [[1, 0, 0, 0]] * 4]
    for pose in bad_poses:
        with pytest.raises(ValueError, match="pose"):
            live.add(1, pose, POINTS)
        with pytest.raises(ValueError, match="pose"):
            live.repose({0: pose})
    with pytest.raises(ValueError, match="already"):
        live.add(0, np.eye(4), POINTS)
    with pytest.raises(ValueError, match="negative"):
        live.add(-1, np.eye(4), POINTS)
    with pytest.raises(ValueError, match="unknown"):
        live.repose({7: np.eye(4)})
    with pytest.raises(ValueError, match="unknown"):
        live.remove([0, 7])
    assert len(live) == 1  # nothing changed


def test_file_errors_are_knnocc_error(knnocc, tmp_path):
    truncated = tmp_path / "t.ply"
    truncated.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
                          b"property float x\nproperty float y\nproperty float z\nend_header\n0123")
    bad_bt = tmp_path / "bad.bt"
    bad_bt.write_bytes(b"# Octomap OcTree binary file\nid OcTree\nsize 9\nres 0.1\ndata\n")
    bad_poses = tmp_path / "poses.txt"
    bad_poses.write_text("0 0 0 0 0 0 0 2\n")
    m = knnocc.OccupancyMap(0.1)
    cases = [
        (lambda: knnocc.read_points(tmp_path / "missing.ply"), "missing.ply", "cannot open"),
        (lambda: knnocc.read_points(truncated), "t.ply", "truncated"),
        (lambda: knnocc.read_points(tmp_path / "x.xyz.bz2"), "x.xyz.bz2", "decompress"),
        (lambda: knnocc.read_points(tmp_path / "x.obj"), "x.obj", "extension"),
        (lambda: knnocc.read_map(bad_bt), "bad.bt", "truncated"),
        (lambda: knnocc.read_map(tmp_path / "none.ot"), "none.ot", "cannot open"),
        (lambda: knnocc.read_sequence(tmp_path / "nothing"), "nothing", ""),
        (lambda: knnocc.read_trajectory(bad_poses), "poses.txt", "quaternion"),
        (lambda: m.write(tmp_path / "no" / "such" / "dir" / "m.bt"), "m.bt", ""),
    ]
    for call, name, problem in cases:
        with pytest.raises(knnocc.Error) as e:
            call()
        assert isinstance(e.value, OSError)
        assert e.value.filename.endswith(name), e.value.filename
        assert str(e.value).startswith(e.value.filename + ": "), str(e.value)
        assert problem in str(e.value) and e.value.strerror in str(e.value)
    assert not list((tmp_path).glob("**/*.tmp-*"))  # no half-written output


def test_memory_limit_is_memory_error(knnocc):
    scan = random_scan(1, n=50000, extent=20.0)
    m = knnocc.OccupancyMap(0.02)
    m.memory_limit = 2_000_000
    assert m.memory_limit == 2_000_000
    with pytest.raises(MemoryError, match="memory limit"):
        m.insert_point_cloud(scan, (0, 0, 0))
    m.memory_limit = 0  # raised: the map takes the scan again
    m.insert_point_cloud(scan[:100], (0, 0, 0))
    assert len(m) > 0
    mapper = knnocc.Mapper(0.02)
    mapper.memory_limit = 2_000_000
    with pytest.raises(MemoryError):
        mapper.insert_keyframe((0, 0, 0), scan)
    live = knnocc.LiveMapper(0.02)
    live.memory_limit = 2_000_000
    assert live.map.memory_limit == 2_000_000
    with pytest.raises(MemoryError):
        live.add(0, np.eye(4), scan)
