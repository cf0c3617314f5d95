"""On the real data in ../shared/data: maps built through Python equal the tool's byte for byte
(.bt and .ot): the TUM clouds with OctoMap's model (through Mapper and through
OccupancyMap.insert_point_cloud with float32 world points, the bench's calls), the ORB-SLAM2
stereo keyframes with the k-NN and robust models (4 m crop, 0.1 m)."""

import numpy as np
import pytest

from conftest import DATA, map_sequence, need_tool, run_tool, skip_all, tool_stats

need_tool()
TUM = DATA / "tum_fr2_pioneer_slam2"
ORB = DATA / "orbslam2_stereo_keyframes"
if not TUM.is_dir() or not ORB.is_dir():
    skip_all(f"the real data is not in {DATA}")


def tool_map(tmp_path, *args):
    bt, ot = tmp_path / "tool.bt", tmp_path / "tool.ot"
    out = run_tool("map", *args, "--out-bt", bt, "--out-ot", ot)
    return bt.read_bytes(), ot.read_bytes(), out


def test_tum_octomap_model(knnocc, tmp_path):
    bt, ot, out = tool_map(tmp_path, "--input", TUM, "--res", 0.05)
    assert "occupied 87069 free 653770" in out
    mapper = map_sequence(knnocc, TUM, 0.05)
    assert mapper.map.to_bytes("bt") == bt and mapper.map.to_bytes("ot") == ot
    m = knnocc.OccupancyMap(0.05)
    for pose, points, _ in knnocc.read_sequence(TUM):
        m.insert_point_cloud(knnocc.to_world(pose, points).astype(np.float32), pose[:3, 3])
    assert m.to_bytes("ot") == ot
    assert m.count_voxels() == (87069, 653770)


@pytest.mark.parametrize("model", ["knn", "robust"])
def test_orbslam_keyframes(knnocc, tmp_path, model):
    bt, ot, out = tool_map(tmp_path, "--input", ORB, "--model", model, "--crop", 4, "--res", 0.1)
    mapper = map_sequence(knnocc, ORB, 0.1, model=model, max_distance=4)
    assert mapper.map.to_bytes("bt") == bt and mapper.map.to_bytes("ot") == ot
    ours, theirs = mapper.statistics(), tool_stats(out)
    assert (ours["map_points"], ours["valid"]) == (theirs["map_points"], theirs["valid"])
    assert f"{ours['mu']:.6f} {ours['sigma']:.6f}" == f"{theirs['mu']:.6f} {theirs['sigma']:.6f}"
