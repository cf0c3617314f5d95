"""Maps built through Python equal the knnocc tool's, byte for byte (.bt and .ot), for the same
input fed the way the tool feeds the library: OctoMap, k-NN, robust and 2022 models (the 2022
model with its first pass's statistics and with running ones), live corrections,
a single point file; queries agree with the tool's voxel list; read_points reads every cloud
format the tool writes. Generated data (`knnocc sim`); the same on real data: test_real_data.py."""

import subprocess

import numpy as np
import pytest

from conftest import TOOL, crop, map_sequence, need_tool, random_scan, run_tool, tool_stats

need_tool()


def tool_map(tmp_path, name, *args):
    """Runs `knnocc map ARGS --out-bt --out-ot`; returns (bt bytes, ot bytes, stdout)."""
    bt, ot = tmp_path / f"{name}.bt", tmp_path / f"{name}.ot"
    out = run_tool("map", *args, "--out-bt", bt, "--out-ot", ot)
    return bt.read_bytes(), ot.read_bytes(), out


@pytest.mark.parametrize("model", ["octomap", "knn", "robust"])
def test_mapper_equals_the_tool(knnocc, drift_scene, tmp_path, model):
    truth = drift_scene / "truth"
    bt, ot, out = tool_map(tmp_path, model, "--input", truth, "--model", model, "--crop", 4,
                           "--res", 0.1)
    mapper = map_sequence(knnocc, truth, 0.1, model=model, max_distance=4)
    assert mapper.map.to_bytes("bt") == bt
    assert mapper.map.to_bytes("ot") == ot
    if model != "octomap":
        ours, theirs = mapper.statistics(), tool_stats(out)
        assert {k: ours[k] for k in ("k", "map_points", "valid")} == \
            {k: theirs[k] for k in ("k", "map_points", "valid")}
        assert f"{ours['mu']:.6f} {ours['sigma']:.6f}" == f"{theirs['mu']:.6f} {theirs['sigma']:.6f}"
    else:
        assert mapper.statistics() == {}


@pytest.mark.parametrize("stats", ["first-pass", "online"])
def test_knn2022_mapper_equals_the_tool(knnocc, drift_scene, tmp_path, stats):
    truth = drift_scene / "truth"
    bt, ot, out = tool_map(tmp_path, f"knn2022_{stats}", "--input", truth, "--model", "knn2022",
                           "--stats", stats, "--res", 0.1)
    params = {}
    if stats == "first-pass":
        first = knnocc.Knn2022FirstPass()
        for pose, points, _ in knnocc.read_sequence(truth):
            first.add(pose[:3, 3], knnocc.to_world(pose, points))
        assert first.count > 0
        assert f"mu {first.mu:.6f} sigma {first.sigma:.6f}" in out  # the tool's own first pass
        params = {"mu": first.mu, "sigma": first.sigma}
    mapper = map_sequence(knnocc, truth, 0.1, model="knn2022", **params)  # whole clouds
    assert mapper.map.to_bytes("bt") == bt
    assert mapper.map.to_bytes("ot") == ot
    assert mapper.statistics() == {}


@pytest.mark.parametrize("model", ["octomap", "knn"])
def test_live_corrections_equal_the_tool(knnocc, drift_scene, tmp_path, model):
    corrections = drift_scene / "corrections"
    bt, ot, _ = tool_map(tmp_path, model, "--input", drift_scene, "--corrections", corrections,
                         "--model", model, "--crop", 4, "--res", 0.1)
    live = knnocc.LiveMapper(0.1, model=model)
    snapshots = 0
    for i, (pose, points, ids) in enumerate(knnocc.read_sequence(drift_scene)):
        live.add(i, pose, *crop(points, ids, 4))
        snapshot = corrections / f"after_{i:06d}.txt"
        if snapshot.exists():
            live.repose(dict(enumerate(knnocc.read_trajectory(snapshot))))
            snapshots += 1
    assert snapshots == 3 and live.last_update["changed"] > 0
    assert live.map.to_bytes("bt") == bt
    assert live.map.to_bytes("ot") == ot
    # And the map of the true poses (the tool's own check, through Python).
    assert live.map == map_sequence(knnocc, drift_scene / "truth", 0.1, model=model,
                                    max_distance=4).map


def test_point_file_and_queries_equal_the_tool(knnocc, tmp_path):
    path = tmp_path / "scan.xyz"
    np.savetxt(path, random_scan(3), fmt="%.9g")
    voxels = tmp_path / "voxels.txt"
    bt, ot, _ = tool_map(tmp_path, "scan", "--input", path, "--res", 0.05, "--out-voxels", voxels)
    points, ids = knnocc.read_points(path)
    assert ids is None and points.dtype == np.float32 and points.shape == (20000, 3)
    m = knnocc.OccupancyMap(0.05)
    m.insert_point_cloud(points, origin=(0, 0, 0))
    assert m.to_bytes("bt") == bt and m.to_bytes("ot") == ot
    # The tool's voxel list (centre, log-odds %.6f): the same voxels, the same values.
    listed = np.loadtxt(voxels)
    assert len(listed) == len(m)
    assert np.all(np.abs(m.logodds_at(listed[:, :3]) - listed[:, 3]) <= 5e-7)
    assert np.array_equal(m.occupancy_at(listed[:, :3]), (listed[:, 3] >= 0).astype(np.int8))


def test_read_points_reads_every_format(knnocc, drift_scene, tmp_path):
    ply = drift_scene / "clouds" / "000000.ply"
    points, ids = knnocc.read_points(ply)
    assert points.dtype == np.float32 and ids.dtype == np.uint64 and len(ids) == len(points) > 0
    seq_pose, seq_points, seq_ids = knnocc.read_sequence(drift_scene)[0]
    assert np.array_equal(seq_points, points) and np.array_equal(seq_ids, ids)
    converted = [("a.pcd", "binary_compressed"), ("b.pcd", "binary"), ("c.pcd", "ascii"),
                 ("d.bin", None), ("e.xyz", None), ("f.txt", None)]
    for name, encoding in converted:
        out = tmp_path / name
        run_tool("convert", ply, out, *(["--encoding", encoding] if encoding else []))
        got, _ = knnocc.read_points(out)
        assert got.dtype == np.float32 and got.shape == points.shape, name
        if encoding in ("binary", "binary_compressed") or name.endswith(".bin"):
            assert np.array_equal(got, points), name
        else:
            assert np.allclose(got, points, rtol=1e-6, atol=1e-6), name
    # The sequence's poses are the trajectory file's.
    assert np.array_equal(knnocc.read_trajectory(drift_scene / "poses.txt")[0], seq_pose)


def write_counted_ply(path, points, ids, evidence):
    """A binary PLY keyframe with ids and the SLAM counters (found, visible, observations)."""
    rows = np.empty(len(points), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("id", "<u4"),
                                        ("found", "<u4"), ("visible", "<u4"),
                                        ("observations", "<u4")])
    for c, name in enumerate("xyz"):
        rows[name] = points[:, c]
    rows["id"] = ids
    for c, name in enumerate(("found", "visible", "observations")):
        rows[name] = evidence[:, c]
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % len(points) +
              "".join("property %s %s\n" % ("float" if n in "xyz" else "uint", n)
                      for n in rows.dtype.names) + "end_header\n")
    path.write_bytes(header.encode() + rows.tobytes())


def test_robust_with_slam_counters_equals_the_tool(knnocc, drift_scene, tmp_path):
    truth, counted = drift_scene / "truth", tmp_path / "counted"
    (counted / "clouds").mkdir(parents=True)
    (counted / "poses.txt").write_bytes((truth / "poses.txt").read_bytes())
    rng = np.random.default_rng(5)
    written = []
    for i, (pose, points, ids) in enumerate(knnocc.read_sequence(truth)):
        visible = rng.integers(1, 40, size=len(points))
        found = (visible * rng.uniform(0.05, 1.0, size=len(points))).astype(np.int64)
        evidence = np.stack([found, visible, rng.integers(1, 12, size=len(points))], axis=1)
        write_counted_ply(counted / "clouds" / ("%06d.ply" % i), points, ids, evidence)
        written.append(evidence)
    bt, ot, _ = tool_map(tmp_path, "robust_counted", "--input", counted, "--model", "robust",
                         "--res", 0.1)
    seq = knnocc.read_sequence(counted)
    with_counters = knnocc.Mapper(0.1, model="robust")
    without = knnocc.Mapper(0.1, model="robust")
    for i, (pose, points, ids) in enumerate(seq):
        assert np.array_equal(seq.evidence(i), written[i])
        world = knnocc.to_world(pose, points)
        with_counters.insert_keyframe(pose[:3, 3], world, ids, evidence=seq.evidence(i))
        without.insert_keyframe(pose[:3, 3], world, ids)
    assert with_counters.map.to_bytes("bt") == bt
    assert with_counters.map.to_bytes("ot") == ot
    assert without.map.to_bytes("bt") != bt  # the counters are used
    assert knnocc.read_sequence(truth).evidence(0) is None


@pytest.mark.parametrize("model", ["octomap", "robust"])
def test_wide_mapper_and_its_tiles_equal_the_tool(knnocc, drift_scene, tmp_path, model):
    """Mapper(..., wide=True) (21-bit keys) inside OctoMap's range is the 16-bit map byte for byte;
    write_tiles writes a tile set that the tool merges into the same files."""
    truth = drift_scene / "truth"
    bt, ot, _ = tool_map(tmp_path, model, "--input", truth, "--model", model, "--crop", 4,
                         "--res", 0.1)
    wide = map_sequence(knnocc, truth, 0.1, model=model, max_distance=4, wide=True)
    assert wide.wide and not map_sequence(knnocc, truth, 0.1, model=model, max_distance=4).wide
    assert wide.map.to_bytes("bt") == bt
    assert wide.map.to_bytes("ot") == ot
    tiles = tmp_path / "tiles"
    assert wide.write_tiles(str(tiles), tile_depth=11) > 1
    assert "key_bits 21" in (tiles / "index.txt").read_text()
    run_tool("merge", tiles, "-o", tmp_path / "merged.ot")
    assert (tmp_path / "merged.ot").read_bytes() == ot


def test_wide_mapper_beyond_octomaps_range(knnocc, tmp_path):
    """Beyond OctoMap's key range a wide Mapper maps every point; its map is refused as one
    OctoMap map (ValueError naming the extent) and written as a tile set, which `knnocc info`
    reads and `knnocc merge` refuses as one file."""
    mapper, narrow, near = knnocc.Mapper(0.1, wide=True), knnocc.Mapper(0.1), knnocc.Mapper(0.1)
    for x in (0.0, 5000.0):
        origin = np.array([x, 0.0, 1.0])
        points = origin + np.array([[2.0, 0.5, -1.0], [3.0, -1.0, 0.5], [2.5, 0.0, 0.0]])
        mapper.insert_keyframe(origin, points)
        narrow.insert_keyframe(origin, points)
        if x == 0.0:
            near.insert_keyframe(origin, points)
    with pytest.raises(ValueError, match="beyond the"):
        mapper.map.occupancy_at(np.zeros((1, 3)))
    assert narrow.map.to_bytes("ot") == near.map.to_bytes("ot")  # 16 bits: the far scan skipped
    tiles = tmp_path / "far"
    assert mapper.write_tiles(str(tiles), tile_depth=8) >= 2
    info = run_tool("info", tiles)
    assert "key bits: 21" in info and "checked: every tile matches the index" in info
    r = subprocess.run([TOOL, "merge", str(tiles), "-o", str(tmp_path / "far.bt")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "beyond the +-3276.8 m" in r.stderr
