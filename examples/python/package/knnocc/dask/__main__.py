# SPDX-License-Identifier: BSD-3-Clause
"""python3 -m knnocc.dask map ...: `knnocc map` on a Dask cluster, for people who do not write
Python (docs/dask.md). One line on stderr and exit status 2 for bad input."""

import argparse
import importlib
import sys

USAGE = """python3 -m knnocc.dask map --input PATH --res R [--model NAME]
                                 (--workers K | --scheduler ADDRESS)
                                 (-o MAP.bt|MAP.ot | --out-tiles DIR) [options]"""

TEXT = """Maps a sequence on a Dask cluster into a tile set and/or one OctoMap file: the same map,
byte for byte, as `knnocc map` in one process with the same options. One task rates every scan in
order; one task per tile maps it; this process writes the index and the merged file. The
sequence and the outputs must be on storage every worker shares with this process. Prints the
tool's summary lines:
  tiles N depth D edge_m E key_bits K
  clouds N points N occupied N free N seconds S
exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem)."""

# --flag: (keyword of knnocc.Mapper, type, models that take it), as `knnocc map` names them.
MODEL_FLAGS = {
    "--prob-hit": ("prob_hit", float, ("octomap",)),
    "--prob-miss": ("prob_miss", float, ("octomap",)),
    "--k": ("k", int, ("knn", "robust")),
    "--w": ("w", float, ("knn", "robust")),
    "--p-upper": ("p_upper", float, ("knn", "robust")),
    "--p-w": ("p_w", float, ("knn", "robust")),
    "--p-free": ("p_free", float, ("knn", "robust")),
    "--s-limit": ("s_limit", float, ("knn", "robust")),
    "--margin-scale": ("margin_scale", float, ("robust",)),
    "--k2022": ("k", int, ("knn2022",)),
    "--inner-range": ("inner_range", float, ("knn2022",)),
    "--p-near": ("p_near", float, ("knn2022",)),
    "--p-far": ("p_far", float, ("knn2022",)),
    "--p-miss": ("p_miss", float, ("knn2022",)),
    "--p-miss-outer": ("p_miss_outer", float, ("knn2022",)),
    "--stats": ("stats", str, ("knn2022",)),
}


class Refused(Exception):
    """A usage error or bad input: one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    def error(self, message):
        raise Refused(message)


def size_in_bytes(text):
    units = {"": 1, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}
    t = text.strip().upper().rstrip("B")
    unit = t[-1] if t and t[-1] in "KMGT" else ""
    try:
        value = float(t[:len(t) - len(unit)])
    except ValueError:
        raise Refused(f"--memory-limit: '{text}' is not a size (e.g. 2G, 500M)") from None
    if not value > 0:
        raise Refused(f"--memory-limit must be > 0, got '{text}'")
    return int(value * units[unit])


def parser():
    p = Parser(prog="python3 -m knnocc.dask map", usage=USAGE, description=TEXT,
               formatter_class=argparse.RawDescriptionHelpFormatter)
    g = p.add_argument_group("input and map")
    g.add_argument("-i", "--input", required=True, metavar="PATH",
                   help="a sequence folder (or a scan graph / point file) the workers can read")
    g.add_argument("-r", "--res", required=True, type=float, metavar="R", help="voxel edge in metres")
    g.add_argument("-m", "--model", default="octomap", choices=("octomap", "knn", "knn2022", "robust"),
                   metavar="NAME", help="octomap (default), knn, knn2022 or robust, as knnocc map")
    g.add_argument("--max-range", type=float, metavar="M", help="OctoMap's maxrange")
    g.add_argument("--crop", type=float, metavar="M", help="drop points farther than M first")
    g.add_argument("--points-frame", default="sensor", choices=("sensor", "world"), metavar="FRAME",
                   help="the clouds' frame: sensor (default) or world")
    g.add_argument("--first", type=int, default=0, metavar="I", help="start at cloud I")
    g.add_argument("--count", type=int, metavar="N", help="map N clouds (default: all the rest)")
    o = p.add_argument_group("outputs")
    o.add_argument("-o", "--output", action="append", default=[], metavar="FILE",
                   help="the merged map, .bt or .ot (repeat for both)")
    o.add_argument("--out-tiles", metavar="DIR", help="the tile set (docs/tiles.md)")
    o.add_argument("--tile-depth", type=int, default=6, metavar="D",
                   help="2^(16-D) voxels per tile edge (default 6; 0: one tile)")
    o.add_argument("--key-bits", type=int, choices=(16, 21), metavar="BITS",
                   help="16 or 21 (default: 21 when the poses go beyond 16 bits' range)")
    o.add_argument("--keep-rated", action="store_true", help="keep DIR/rated (the rated keyframes)")
    c = p.add_argument_group("cluster")
    c.add_argument("--workers", type=int, metavar="K",
                   help="a local cluster of K worker processes (one thread each)")
    c.add_argument("--scheduler", metavar="ADDRESS", help="a running scheduler, e.g. tcp://host:8786")
    c.add_argument("--memory-limit", metavar="SIZE",
                   help="each tile's map at most SIZE on a worker (and 3/4 of its memory limit)")
    m = p.add_argument_group("model parameters (as knnocc map --help)")
    for flag, (_, kind, models) in MODEL_FLAGS.items():
        m.add_argument(flag, type=kind, metavar="X", help="--model " + "/".join(models))
    return p


def model_params(args):
    params = {}
    for flag, (key, _, models) in MODEL_FLAGS.items():
        value = getattr(args, flag[2:].replace("-", "_"))
        if value is None:
            continue
        if args.model not in models:
            raise Refused(f"{flag} needs --model {' or '.join(models)}")
        params[key] = value
    return params


def connect(args):
    """A client of a new local cluster or of a running scheduler; Refused when unreachable."""
    from distributed import Client, LocalCluster
    if (args.workers is None) == (args.scheduler is None):
        raise Refused("give --workers K (a local cluster) or --scheduler ADDRESS, one of them")
    if args.workers is not None:
        if args.workers < 1:
            raise Refused(f"--workers must be >= 1, got {args.workers}")
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, host="127.0.0.1")
        return Client(cluster), cluster
    try:
        return Client(args.scheduler, timeout="10s"), None
    except (OSError, TimeoutError) as e:
        raise Refused(f"{args.scheduler}: cannot reach the scheduler ({e})") from None


def check_workers(client):
    """Every worker imports knnocc, or Refused naming the worker."""
    try:
        client.run(importlib.import_module, "knnocc")
    except ModuleNotFoundError as e:
        raise Refused(f"a worker has no knnocc module ({e}); install it where every worker "
                      "runs (cmake --install build, or PYTHONPATH)") from None


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print("usage: " + USAGE + "\n\n" + TEXT +
              "\n\ncommands: map (python3 -m knnocc.dask map --help)")
        return 0
    if argv[0] != "map":
        raise Refused(f"unknown command '{argv[0]}' (the one command is: map)")
    args = parser().parse_args(argv[1:])
    outputs = args.output
    if not outputs and not args.out_tiles:
        raise Refused("needs -o MAP.bt|MAP.ot or --out-tiles DIR (or both)")
    if len(outputs) > 2 or len({o.lower()[-3:] for o in outputs}) != len(outputs):
        raise Refused("-o takes at most one .bt and one .ot file")
    params = model_params(args)
    import knnocc.dask as kd
    client, cluster = connect(args)
    try:
        check_workers(client)
        kd.map_sequence(
            client, args.input, res=args.res, model=args.model, out=outputs or None,
            out_tiles=args.out_tiles, tile_depth=args.tile_depth, key_bits=args.key_bits,
            crop=args.crop, max_range=args.max_range, points_frame=args.points_frame,
            first=args.first, count=args.count, keep_rated=args.keep_rated,
            memory_limit=size_in_bytes(args.memory_limit) if args.memory_limit else None,
            **params)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


def run():
    try:
        sys.exit(main(sys.argv[1:]))
    except Refused as e:
        print(f"knnocc.dask: {e}", file=sys.stderr)
        sys.exit(2)
    except (OSError, ValueError, MemoryError) as e:  # knnocc.Error is an OSError
        print(f"knnocc.dask: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    run()
