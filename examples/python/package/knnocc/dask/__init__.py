# SPDX-License-Identifier: BSD-3-Clause
"""knnocc on a Dask cluster: a sequence mapped into a tile set by the cluster's workers, the same
map byte for byte as `knnocc map` in one process (docs/dask.md).

    from distributed import Client, LocalCluster
    import knnocc.dask

    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        knnocc.dask.map_sequence(client, "drive", res=0.1, out_tiles="drive_tiles",
                                 out="drive.bt")

What runs where (docs/tiles.md for why the map is exact):
  - one task rates every scan in order (the rating pass: k-NN statistics, the robust model's
    ledger; the map point cloud of keyframe t needs keyframes 0..t) and writes rated keyframes
    into the tile set's folder, which the workers and this process share;
  - one task per tile maps it from the rated keyframes that reach it and writes its .ot file;
    tasks carry paths and small parameters only, workers read the files themselves;
  - this process writes the index, and the merged .bt/.ot on request, streamed tile by tile.
A worker lost in the middle of a tile (killed, out of memory) has its task run again elsewhere
(Dask's own retry); the tile's file is written atomically, and a killed writer's temporary is
removed before the tile set is committed, so the map is the same. A task that fails for bad input
stops the run with the file's name, and nothing is left behind. Dask is imported when a function
here is called, not before.
"""

import os
import pathlib
import shutil
import sys
import tempfile
import time
import uuid

import knnocc
from knnocc import _knnocc

__all__ = ["map_sequence", "MODELS"]

MODELS = ("octomap", "knn", "knn2022", "robust")
MIN_RESOLUTION = 1e-4  # as `knnocc map --res`
WORKER_SHARE = 0.75  # of a worker's memory limit a tile's map may take (below Dask's pause)


# ---- tasks (run on the workers; each imports knnocc there) -----------------------------------

def _rate(sequence, rated, res, model, key_bits, crop, world_points, first, count, params):
    try:
        os.mkdir(rated)  # inside the staged tile set; gone when the run was given up
    except FileExistsError:
        pass  # a retry of this task after a lost worker
    return _knnocc._rate_sequence(sequence, rated, res, model, key_bits=key_bits, crop=crop,
                                  world_points=world_points, first=first, count=count, **params)


def _worker_tile_limit(requested):
    """The memory a tile's map may take on this worker: `requested` (bytes, 0: none), at most
    WORKER_SHARE of the worker's memory limit, so that a tile too large is refused by knnocc with
    a message instead of the worker being killed by Dask."""
    limit = requested or 0
    try:
        from distributed import get_worker
        worker = get_worker()
        manager = getattr(worker, "memory_manager", None)
        worker_limit = getattr(manager, "memory_limit", None) or getattr(worker, "memory_limit", 0)
    except (ImportError, ValueError):
        worker_limit = 0
    if worker_limit:
        cap = int(WORKER_SHARE * worker_limit)
        limit = min(limit, cap) if limit else cap
    return int(limit)


def _tile(rated, staging, depth, coord, memory_limit):
    return _knnocc._map_tile(rated, staging, depth, tuple(coord), _worker_tile_limit(memory_limit))


# ---- the driver ------------------------------------------------------------------------------

def _is_tile_set(path):
    index = pathlib.Path(path) / "index.txt"
    try:
        with open(index, "rb") as f:
            return f.read(16) == b"knnocc tile set "
    except OSError:
        return False


def _check_folder(path):
    """A tile set's target: absent, empty, or an earlier tile set (replaced); knnocc.Error
    otherwise, before any work (as `knnocc map --out-tiles`)."""
    p = pathlib.Path(path)
    if p.is_symlink() or (p.exists() and not p.is_dir()):
        raise knnocc.Error(f"{path}: exists and is not a folder; give a new folder name")
    if p.is_dir() and any(p.iterdir()) and not _is_tile_set(p):
        raise knnocc.Error(f"{path}: folder is not empty; give a new or empty folder (nothing is "
                           "overwritten)")
    parent = p.resolve().parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise knnocc.Error(f"{path}: folder '{parent}' does not exist or is not writable")


def _outputs(out):
    """The merged files asked for: None, a path, or a list of at most one .bt and one .ot."""
    files = [] if out is None else [out] if isinstance(out, (str, os.PathLike)) else list(out)
    suffixes = [pathlib.Path(f).suffix.lower() for f in files]
    for f, suffix in zip(files, suffixes):
        if suffix not in (".bt", ".ot"):
            raise ValueError(f"out {f}: the extension must be .bt or .ot (the merged map)")
        parent = pathlib.Path(f).resolve().parent
        if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
            raise knnocc.Error(f"{f}: folder '{parent}' does not exist or is not writable")
    if len(set(suffixes)) != len(suffixes):
        raise ValueError("out takes at most one .bt and one .ot file")
    return [str(f) for f in files]


def _key_bits(sequence, res, crop, max_range, first, count, key_bits):
    """--key-bits: given, or 21 when the poses go beyond 16-bit keys' range (with a note)."""
    if key_bits is not None:
        if key_bits not in (16, 21):
            raise ValueError(f"key_bits must be 16 or 21, got {key_bits}")
        return key_bits
    try:
        reach = _knnocc._sensor_reach(str(sequence), int(first), count)
    except knnocc.Error:
        return 16  # not readable here: the rating task says what is wrong
    margin = crop if crop else (max_range if max_range and max_range > 0 else 0.0)
    if reach + margin < 32768.0 * res:
        return 16
    print(f"knnocc.dask: {sequence}: the sensor travels {reach:.1f} m from the origin, beyond "
          f"the +-{32768.0 * res:.1f} m of OctoMap's 16-bit keys at res {res:g}: mapping with "
          "21-bit keys", file=sys.stderr)
    return 21


def _check_options(res, model, tile_depth, crop, max_range, points_frame, params):
    if not (isinstance(res, (int, float)) and res >= MIN_RESOLUTION and res < float("inf")):
        raise ValueError(f"res must be a number >= {MIN_RESOLUTION:g} (metres), got {res!r}")
    if model not in MODELS:
        raise ValueError(f"model must be one of {', '.join(MODELS)}, got {model!r}")
    if not (isinstance(tile_depth, int) and 0 <= tile_depth <= 13):
        raise ValueError(f"tile_depth must be an integer in [0, 13], got {tile_depth!r}")
    if crop is not None and not crop > 0:
        raise ValueError(f"crop must be > 0, got {crop!r}")
    if max_range is not None and (max_range == 0 or max_range != max_range):
        raise ValueError("max_range must be > 0, or < 0 for no limit")
    if points_frame not in ("sensor", "world"):
        raise ValueError(f"points_frame must be 'sensor' or 'world', got {points_frame!r}")
    mapper_params = {k: v for k, v in params.items() if k != "stats"}
    if max_range is not None:
        mapper_params["max_range"] = max_range
    knnocc.Mapper(res, model=model, **mapper_params)  # ValueError for a bad parameter, now


class _Progress:
    """The tool's progress line on stderr (only on a terminal)."""

    def __init__(self, what, total):
        self.what, self.total, self.start = what, total, time.monotonic()
        self.on = sys.stderr.isatty() and total > 1

    def update(self, done):
        if not self.on:
            return
        filled = 30 * done // self.total
        elapsed = time.monotonic() - self.start
        sys.stderr.write(f"\r\033[K{self.what} [{'#' * filled}{' ' * (30 - filled)}] "
                         f"{done}/{self.total}  {elapsed:.0f} s")
        sys.stderr.flush()

    def finish(self):
        if self.on:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()


def _commit(staging, target):
    """Renames the staged tile set into place (an earlier tile set there is replaced)."""
    old = None
    if os.path.isdir(target):
        try:
            os.rmdir(target)  # empty
        except OSError:
            old = staging + ".old"
            os.rename(target, old)
    os.rename(staging, target)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def _discard(staging):
    """Removes a staged tile set that will not be committed. Renamed first: a task still running
    on a worker (Dask cannot stop one) then fails to write instead of adding files to a folder
    being removed."""
    trash = staging + ".discard"
    try:
        os.rename(staging, trash)
    except OSError:
        trash = staging
    shutil.rmtree(trash, ignore_errors=True)


def _remove_temporaries(folder):
    """Temporaries a killed writer left (AtomicFile's NAME.tmp-XXXXXX)."""
    for p in pathlib.Path(folder).glob("*.tmp-*"):
        if p.is_file():
            p.unlink()


def _run_tiles(client, rated, staging, depth, memory_limit, token, progress):
    from distributed import as_completed

    coords = _knnocc._tiles_reached(rated, depth)
    futures = [client.submit(_tile, rated, staging, depth, c, memory_limit, pure=False,
                             key=f"knnocc-tile-{c[0]}_{c[1]}_{c[2]}-{token}") for c in coords]
    bar = _Progress("tiles", len(futures)) if progress else None
    entries = []
    try:
        for done, future in enumerate(as_completed(futures), 1):
            entry = future.result()  # a task's exception is raised here
            if entry is not None:
                entries.append(entry)
            if bar:
                bar.update(done)
    except BaseException:
        client.cancel(futures)
        raise
    finally:
        if bar:
            bar.finish()
    return entries


def map_sequence(client, sequence, *, res, model="octomap", out=None, out_tiles=None,
                 tile_depth=6, key_bits=None, crop=None, max_range=None, points_frame="sensor",
                 first=0, count=None, memory_limit=None, keep_rated=False, progress=True,
                 quiet=False, **params):
    """Maps `sequence` (a sequence folder, or a scan graph / point file that the workers can read)
    on the cluster of `client` into the tile set `out_tiles` and/or the merged OctoMap file(s)
    `out` (a .bt or .ot path, or a list of one of each): byte for byte what
    `knnocc map --input SEQUENCE --res RES --model MODEL` writes in one process (coloured clouds
    excepted: the tiles keep no colours, so an .ot is a plain OcTree where the tool writes a
    ColorOcTree). The sequence and the outputs must be on storage the workers share with this
    process (an output folder is written by the workers).

    Options as `knnocc map`'s: res, model ('octomap', 'knn', 'knn2022', 'robust'), crop, max_range,
    points_frame ('sensor' or 'world'), first and count (the scans mapped), tile_depth, key_bits
    (16, 21, or None: 21 when the poses go beyond 16 bits' range), keep_rated (keep the rated
    keyframes in OUT_TILES/rated); params: the model's parameters as knnocc.Mapper takes them, and
    stats='first-pass' or 'online' for the 2022 model. memory_limit: bytes a tile's map may take
    on a worker (at most 3/4 of the worker's own memory limit, whatever is asked). Prints the
    tool's summary lines unless quiet; returns them as a dict.

    Errors: ValueError for bad options, knnocc.Error for files (a sequence the workers cannot
    read names it; a tile too large for its memory names the tile); no partial tile set or map
    is left.
    """
    t0 = time.monotonic()
    files = _outputs(out)
    if not files and out_tiles is None:
        raise ValueError("map_sequence needs out (a .bt/.ot file) or out_tiles (a folder), or both")
    _check_options(res, model, tile_depth, crop, max_range, points_frame, params)
    if out_tiles is not None:
        _check_folder(out_tiles)
        folder = pathlib.Path(out_tiles).resolve()
        for f in files:
            if folder in pathlib.Path(f).resolve().parents:
                raise ValueError(f"out {f}: inside the out_tiles folder {out_tiles}; write it "
                                 "beside the tile set")
    bits = _key_bits(sequence, res, crop, max_range, first, count, key_bits)
    if bits == 21 and tile_depth == 0:
        raise ValueError("tile_depth 0 (one tile of OctoMap's whole key range) needs 16-bit keys")
    # Staged beside the tile set, or beside the first merged file when no tile set is kept (then
    # the staging folder is all there is: nothing is ever committed to a folder name not given).
    name = str(out_tiles) if out_tiles is not None else files[0]
    parent = os.path.dirname(os.path.abspath(name))
    staging = tempfile.mkdtemp(prefix=os.path.basename(os.path.abspath(name)) + ".tmp-",
                               dir=parent)
    rated = os.path.join(staging, "rated")
    token = uuid.uuid4().hex[:8]
    run_params = dict(params)
    if max_range is not None:
        run_params["max_range"] = max_range
    try:
        totals = client.submit(_rate, str(sequence), rated, float(res), model, bits,
                               float(crop) if crop else -1.0, points_frame == "world", int(first),
                               count, run_params, pure=False, key=f"knnocc-rate-{token}").result()
        entries = _run_tiles(client, rated, staging, tile_depth, memory_limit or 0, token,
                             progress)
        _remove_temporaries(staging)
        options = " ".join(f"{k}={v}" for k, v in sorted(params.items()))
        _knnocc._write_tile_index(staging, rated, tile_depth, model, options, str(sequence),
                                  int(first), int(totals["clouds"]), entries)
        if not keep_rated:
            shutil.rmtree(rated)
        # The merged files are written before the tile set is committed and renamed in one group:
        # a merge that fails (a map beyond OctoMap's key range) leaves no tile set and no file.
        if files:
            try:
                knnocc.merge_tiles(staging, files)
            except knnocc.Error as e:
                if e.filename != staging:
                    raise
                raise knnocc.Error(f"{files[0]}: {e.strerror}") from None
        if out_tiles is not None:
            _commit(staging, str(out_tiles))
        else:
            shutil.rmtree(staging)
    except BaseException:
        _discard(staging)
        raise
    written = ([] if out_tiles is None else [str(out_tiles)]) + files
    occupied = sum(e["occupied"] for e in entries)
    free = sum(e["free"] for e in entries)
    seconds = time.monotonic() - t0
    summary = dict(totals, tiles=len(entries), depth=tile_depth, key_bits=bits,
                   occupied=occupied, free=free, seconds=seconds, written=written)
    if not quiet:
        if "map_points" in totals:
            print(f"knn k {totals['k']} map_points {totals['map_points']} valid {totals['valid']} "
                  f"mu {totals['mu']:.6f} sigma {totals['sigma']:.6f} rays {totals['rays']} of "
                  f"{totals['rated']} median_keyframe_ms {totals['median_keyframe_ms']:.3f}")
        print(f"tiles {len(entries)} depth {tile_depth} edge_m {res * 2 ** (16 - tile_depth):g} "
              f"key_bits {bits}")
        print(f"clouds {totals['clouds']} points {totals['points']} occupied {occupied} "
              f"free {free} seconds {seconds:.3f}")
        print("wrote " + ", ".join(written))
    return summary
