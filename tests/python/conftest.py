"""Shared by the Python tests (run by ctest with the interpreter the module was built for):
where the tool and the real data are, how to run the tool, and a small generated scene."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("KNNOCC_DATA_DIR") or ROOT.parent / "shared" / "data")
TOOL = os.environ.get("KNNOCC_TOOL", "")


def skip_all(reason):
    """Skips every test of the calling module; ctest then shows the test as SKIPPED."""
    pytest.skip("KNNOCC_SKIPPED: " + reason, allow_module_level=True)


def need_tool():
    if not TOOL or not os.access(TOOL, os.X_OK):
        skip_all("the knnocc tool is not built (KNNOCC_TOOL)")


def run_tool(*args):
    """Runs `knnocc ARGS...`; returns its stdout, fails the test on a non-zero exit."""
    r = subprocess.run([TOOL, *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, f"knnocc {' '.join(map(str, args))}: {r.stderr}"
    return r.stdout


def tool_stats(stdout):
    """The tool's `knn k K map_points N valid N mu X sigma X ...` line as a dict."""
    for line in stdout.splitlines():
        if line.startswith("knn "):
            f = line.split()
            return {"k": int(f[2]), "map_points": int(f[4]), "valid": int(f[6]),
                    "mu": float(f[8]), "sigma": float(f[10])}
    raise AssertionError("no knn line in: " + stdout)


def crop(points, ids, max_distance):
    """The tool's --crop, bit for bit: points within max_distance of the sensor (sensor frame,
    distance in double)."""
    if max_distance is None:
        return points, ids
    p = points.astype(np.float64)
    keep = np.sqrt(p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1] + p[:, 2] * p[:, 2]) <= max_distance
    return points[keep], (None if ids is None else ids[keep])


def map_sequence(knnocc, path, resolution, model="octomap", max_distance=None, **params):
    """A Mapper fed as `knnocc map --input PATH --model MODEL [--crop M]` feeds the library."""
    mapper = knnocc.Mapper(resolution, model=model, **params)
    for pose, points, ids in knnocc.read_sequence(path):
        points, ids = crop(points, ids, max_distance)
        mapper.insert_keyframe(pose[:3, 3], knnocc.to_world(pose, points), ids)
    return mapper


@pytest.fixture(scope="session")
def knnocc():
    import knnocc as module
    return module


@pytest.fixture(scope="session")
def drift_scene(tmp_path_factory):
    """`knnocc sim --drift`: 30 keyframes with ids, drifting poses, SLAM correction snapshots
    and the true poses (truth/)."""
    need_tool()
    out = tmp_path_factory.mktemp("sim") / "drift"
    run_tool("sim", "--out", out, "--seed", 3, "--keyframes", 30, "--drift", 0.3)
    return out


def random_scan(seed, n=20000, extent=3.0):
    """A cloud of n points on a few planes and in free space around the origin (float32)."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(-extent, extent, size=(n, 3))
    p[: n // 2, 2] = -1.0 + 0.01 * rng.standard_normal(n // 2)  # a floor
    p[n // 2: 3 * n // 4, 0] = 2.5  # a wall
    return p.astype(np.float32)
