"""knnocc.dask on a LocalCluster of 2 worker processes on 127.0.0.1 (dashboard off): the map equals
`knnocc map`'s byte for byte for every model on the stereo keyframes and TUM at 1, about 8 and
about 64 tiles; a worker killed (SIGKILL) in the middle of a tile changes nothing; bad input stops
the run with the file's name and leaves nothing; the command line's errors are one line, exit 2."""

import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import pytest

from conftest import DATA, TOOL, need_tool, run_tool, skip_all

need_tool()
distributed = pytest.importorskip("distributed", reason="KNNOCC_SKIPPED: python3-distributed "
                                  "is not installed")

import knnocc.dask  # noqa: E402  (after the skip)

STEREO = DATA / "orbslam2_stereo_keyframes"
TUM = DATA / "tum_fr2_pioneer_slam2"
if not STEREO.is_dir() or not TUM.is_dir():
    skip_all("../shared/data (the stereo keyframes and TUM) is not available")

# Tile depths that give 1, about 8 and about 64 tiles at these resolutions.
DEPTHS = {"stereo": (0, 8, 10), "TUM": (0, 10, 12)}
SETS = {"stereo": (STEREO, 0.05, ["--crop", 6]), "TUM": (TUM, 0.1, [])}


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, host="127.0.0.1",
                                       memory_limit="2GB")
    c = distributed.Client(cluster, timeout="60s")
    yield c
    c.close()
    cluster.close()


def tool_files(tmp_path, name, seq, res, extra, model):
    bt, ot = tmp_path / f"{name}.bt", tmp_path / f"{name}.ot"
    run_tool("map", "--input", seq, "--res", res, "--model", model, *extra, "-o", bt, "-o", ot)
    return bt.read_bytes(), ot.read_bytes()


@pytest.mark.parametrize("model", ["octomap", "knn", "knn2022", "robust"])
@pytest.mark.parametrize("name", ["stereo", "TUM"])
def test_the_cluster_maps_the_tools_map(client, tmp_path, name, model):
    seq, res, extra = SETS[name]
    bt, ot = tool_files(tmp_path, "tool", seq, res, extra, model)
    crop = extra[1] if extra else None
    counts = []
    for depth in DEPTHS[name]:
        out_bt, out_ot = tmp_path / f"d{depth}.bt", tmp_path / f"d{depth}.ot"
        s = knnocc.dask.map_sequence(client, str(seq), res=res, model=model, crop=crop,
                                     tile_depth=depth, out=[str(out_bt), str(out_ot)],
                                     out_tiles=str(tmp_path / f"tiles{depth}"), quiet=True)
        assert out_bt.read_bytes() == bt, f"{name} {model} depth {depth}: .bt differs"
        assert out_ot.read_bytes() == ot, f"{name} {model} depth {depth}: .ot differs"
        counts.append(s["tiles"])
    assert counts[0] == 1 and 4 <= counts[1] <= 24 and 25 <= counts[2] <= 160, counts


def test_a_worker_killed_in_the_middle_of_a_tile_changes_nothing(client, tmp_path):
    """SIGKILL the worker that runs a tile task once the tiles are running: Dask runs its tasks
    again on the other (or restarted) worker, and the map is the same."""
    seq, res, extra = SETS["TUM"]
    bt, _ = tool_files(tmp_path, "tool", seq, 0.05, [], "octomap")
    killed = []

    def kill_a_tile_worker():
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not killed:
            for worker, keys in client.processing().items():
                if any(str(k).startswith("knnocc-tile-") for k in keys):
                    pid = client.run(os.getpid, workers=[worker])[worker]
                    os.kill(pid, signal.SIGKILL)
                    killed.append(worker)
                    return
            time.sleep(0.005)

    killer = threading.Thread(target=kill_a_tile_worker)
    killer.start()
    out = tmp_path / "killed.bt"
    knnocc.dask.map_sequence(client, str(seq), res=0.05, tile_depth=11, out=str(out), quiet=True)
    killer.join()
    assert killed, "no tile task was seen running"
    assert out.read_bytes() == bt
    client.wait_for_workers(2, timeout=60)  # the nanny restarts the killed worker


def test_bad_input_stops_the_run_naming_the_file_and_leaves_nothing(client, tmp_path):
    seq = tmp_path / "seq"
    (seq / "clouds").mkdir(parents=True)
    (seq / "poses.txt").write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n")
    (seq / "clouds" / "000000.ply").write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
        b"property float y\nproperty float z\nend_header\n" + b"\0" * 12)
    (seq / "clouds" / "000001.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 5\n")
    out, tiles = tmp_path / "bad.bt", tmp_path / "bad_tiles"
    with pytest.raises(knnocc.Error, match="000001.ply"):
        knnocc.dask.map_sequence(client, str(seq), res=0.1, out=str(out), out_tiles=str(tiles),
                                 quiet=True)
    assert not out.exists() and not tiles.exists()
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]
    with pytest.raises(knnocc.Error, match="nowhere: cannot open"):
        knnocc.dask.map_sequence(client, str(tmp_path / "nowhere"), res=0.1, out=str(out),
                                 quiet=True)
    with pytest.raises(ValueError, match="unknown parameter 'kk'"):
        knnocc.dask.map_sequence(client, str(seq), res=0.1, model="knn", out=str(out), kk=3)


def far_sequence(folder, x):
    """Two scans of a wall 2 m ahead, the second taken `x` metres from the first."""
    import struct
    (folder / "clouds").mkdir(parents=True)
    (folder / "poses.txt").write_text(f"0 0 0 0 0 0 0 1\n1 {x} 0 0 0 0 0 1\n")  # t x y z q
    points = [(2.0, 0.1 * i, 0.1 * j) for i in range(-5, 6) for j in range(-5, 6)]
    body = b"".join(struct.pack("<3f", *p) for p in points)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n").encode()
    for i in range(2):
        (folder / "clouds" / f"{i:06d}.ply").write_bytes(header + body)
    return folder


def test_outputs_are_all_or_nothing_and_no_folder_is_guessed(client, tmp_path):
    # Without out_tiles nothing is written beside the map but the map: a folder named after it
    # is left alone.
    seq = far_sequence(tmp_path / "near", 10.0)
    mine = tmp_path / "m.bt.tiles"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    s = knnocc.dask.map_sequence(client, str(seq), res=0.1, out=str(tmp_path / "m.bt"),
                                 quiet=True)
    assert s["key_bits"] == 16 and (tmp_path / "m.bt").stat().st_size > 0
    assert (mine / "notes.txt").read_text() == "mine"
    # A merged file inside the tile set's folder is refused before any work.
    (tmp_path / "t").mkdir()
    with pytest.raises(ValueError, match="inside the out_tiles folder"):
        knnocc.dask.map_sequence(client, str(seq), res=0.1, out=str(tmp_path / "t" / "m.bt"),
                                 out_tiles=str(tmp_path / "t"), quiet=True)
    assert not any((tmp_path / "t").iterdir())
    # Upper-case extensions are OctoMap files too.
    knnocc.dask.map_sequence(client, str(seq), res=0.1, out=str(tmp_path / "UP.BT"), quiet=True)
    assert (tmp_path / "UP.BT").read_bytes() == (tmp_path / "m.bt").read_bytes()
    # A map beyond OctoMap's key range is mapped with 21-bit keys (from the poses, as the tool
    # decides); merging it into one .bt is refused, and then neither the tile set nor the file
    # is written.
    far = far_sequence(tmp_path / "far", 4000.0)
    from knnocc import _knnocc
    assert _knnocc._sensor_reach(str(far)) == 4000.0
    out, tiles = tmp_path / "far.bt", tmp_path / "far_tiles"
    with pytest.raises(knnocc.Error, match="key range|beyond"):
        knnocc.dask.map_sequence(client, str(far), res=0.1, out=str(out), out_tiles=str(tiles),
                                 quiet=True)
    assert not out.exists() and not tiles.exists()
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name or ".discard" in p.name]
    s = knnocc.dask.map_sequence(client, str(far), res=0.1, out_tiles=str(tiles), quiet=True)
    assert s["key_bits"] == 21 and s["tiles"] >= 2 and (tiles / "index.txt").is_file()


def test_a_tile_larger_than_its_memory_is_refused_with_a_message(client, tmp_path):
    out = tmp_path / "small.bt"
    with pytest.raises(knnocc.Error, match="needs more than its memory limit"):
        knnocc.dask.map_sequence(client, str(TUM), res=0.05, tile_depth=4, out=str(out),
                                 memory_limit=200_000, quiet=True)
    assert not out.exists()


def dask_command(*args):
    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "knnocc.dask", *map(str, args)],
                          capture_output=True, text=True, env=env, timeout=300)


def test_the_command_maps_as_the_tool(tmp_path):
    bt, _ = tool_files(tmp_path, "tool", STEREO, 0.05, ["--crop", 6], "robust")
    out = tmp_path / "cmd.bt"
    r = dask_command("map", "--input", STEREO, "--res", 0.05, "--model", "robust", "--crop", 6,
                     "--workers", 2, "-o", out, "--tile-depth", 9)
    assert r.returncode == 0, r.stderr
    assert "tiles " in r.stdout and "clouds 249 points" in r.stdout
    assert out.read_bytes() == bt


@pytest.mark.parametrize("args, message", [
    (["map", "--input", STEREO, "--res", 0.1, "--scheduler", "tcp://127.0.0.1:9", "-o", "x.bt"],
     "tcp://127.0.0.1:9: cannot reach the scheduler"),
    (["map", "--input", STEREO, "--res", 0.1, "--workers", 1], "needs -o MAP.bt|MAP.ot"),
    (["map", "--input", STEREO, "--res", 0.1, "-o", "x.bt"], "give --workers K"),
    (["map", "--input", STEREO, "--res", 0.1, "--workers", 1, "-o", "x.bt", "--k", 3],
     "--k needs --model knn or robust"),
    (["frobnicate"], "unknown command 'frobnicate'"),
])
def test_the_commands_errors_are_one_line(tmp_path, args, message):
    r = dask_command(*args)
    assert r.returncode == 2
    assert message in r.stderr and r.stderr.count("\n") == 1, r.stderr


def test_a_worker_without_knnocc_is_named(tmp_path):
    """A worker whose Python cannot import knnocc (PYTHONPATH without it)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                  "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", str(tmp_path / "s.json")],
                                 env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / "s.json").exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        import json
        address = json.loads((tmp_path / "s.json").read_text())["address"]
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address,
                                   "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"],
                                  env=env, cwd=str(tmp_path), stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        with distributed.Client(address, timeout="60s") as c:
            c.wait_for_workers(1, timeout=60)
        r = dask_command("map", "--input", STEREO, "--res", 0.1, "--scheduler", address,
                         "-o", tmp_path / "x.bt")
        assert r.returncode == 2
        assert "a worker has no knnocc module" in r.stderr, r.stderr
    finally:
        for p in (worker, scheduler):
            if p is not None:
                p.kill()
                p.wait()
