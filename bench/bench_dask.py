#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""bench_dask: knnocc.dask on a LocalCluster of 1 and of 2 worker processes against the plain
`knnocc map` on one thread, in the same run, on the simulated drive (knnocc sim --scene drive):
wall time (merge included), each worker's peak resident memory, the driver's, and the ratios;
the rating pass's share of a one-process run for every model on the stereo keyframes; and that
every map is byte for byte the tool's.

usage: PYTHONPATH=build/python python3 bench/bench_dask.py --drive DIR [--res R] [--depth D]
           [--data DIR] [--out DIR] [--tool build/bin/knnocc] [--count N]

Goals (issue: Dask): identical maps; 2 workers <= 0.6x one worker's wall time; one worker <=
1.25x the plain tool; each worker's peak <= 15 % of the tool's peak with 64 tiles, the driver's
<= 10 %; the knn model's rating pass <= 30 % of its one-process mapping time.
"""

import argparse
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import time


def run_tool(tool, *args):
    """Runs the tool as a child: (wall seconds, its peak RSS in MB, stdout)."""
    t0 = time.monotonic()
    p = subprocess.Popen([tool, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = p.stdout.read().decode()
    err = p.stderr.read().decode()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    seconds = time.monotonic() - t0
    if p.returncode:
        sys.exit(f"bench_dask: {tool} {' '.join(map(str, args))}: {err.strip()}")
    return seconds, usage.ru_maxrss / 1024.0, out


def worker_peak_mb():
    import resource as r
    return r.getrusage(r.RUSAGE_SELF).ru_maxrss / 1024.0


def dask_run(workers, drive, res, depth, out, count):
    """knnocc.dask on a fresh LocalCluster: wall seconds, the workers' peak MB, the summary."""
    import distributed
    import knnocc.dask
    cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, host="127.0.0.1")
    client = distributed.Client(cluster)
    try:
        t0 = time.monotonic()
        summary = knnocc.dask.map_sequence(client, str(drive), res=res, tile_depth=depth,
                                           out=str(out), count=count, quiet=True,
                                           progress=False)
        seconds = time.monotonic() - t0
        peaks = client.run(worker_peak_mb)
    finally:
        client.close()
        cluster.close()
    return seconds, sorted(peaks.values()), summary


def rating_share(tool, stereo, out):
    """The rating pass of each model on the stereo set against its one-process mapping time."""
    import knnocc
    from knnocc import _knnocc
    print("\nthe rating pass against a one-process map, stereo keyframes, res 0.05, crop 6:")
    for model in ("octomap", "knn", "knn2022", "robust"):
        seconds, _, _ = run_tool(tool, "map", "--input", stereo, "--res", 0.05, "--crop", 6,
                                 "--model", model, "-o", out / f"stereo_{model}.ot")
        rated = out / f"rated_{model}"
        shutil.rmtree(rated, ignore_errors=True)
        rated.mkdir()
        t0 = time.monotonic()
        _knnocc._rate_sequence(str(stereo), str(rated), 0.05, model, crop=6.0)
        rate = time.monotonic() - t0
        print(f"  {model:8s} one process {seconds:7.3f} s, rating pass {rate:7.3f} s: "
              f"{100 * rate / seconds:5.1f} %" + ("  (goal <= 30 %)" if model == "knn" else ""))
        shutil.rmtree(rated, ignore_errors=True)
    del knnocc


def main():
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--drive", required=True)
    a.add_argument("--res", type=float, default=0.2)
    a.add_argument("--depth", type=int, default=5)
    a.add_argument("--count", type=int, default=None)
    a.add_argument("--data", default="../shared/data")
    a.add_argument("--out", default="build/bench_dask")
    a.add_argument("--tool", default="build/bin/knnocc")
    args = a.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    drive = pathlib.Path(args.drive)
    count = ["--count", args.count] if args.count else []
    print(f"bench_dask: drive {drive} at {args.res} m, tile depth {args.depth}")
    seconds, peak, line = run_tool(args.tool, "map", "--input", drive, "--res", args.res,
                                   "--threads", 1, *count, "-o", out / "tool.ot")
    print(f"  knnocc map, one thread:  {seconds:8.2f} s, peak {peak:8.1f} MB  ({line.strip()})")
    results = {}
    for workers in (1, 2):
        target = out / f"dask{workers}.ot"
        s, peaks, summary = dask_run(workers, drive, args.res, args.depth, target, args.count)
        same = target.read_bytes() == (out / "tool.ot").read_bytes()
        results[workers] = s
        print(f"  knnocc.dask, {workers} worker{'s' if workers > 1 else ' '}: {s:8.2f} s "
              f"({s / seconds:.2f}x the tool), workers' peaks "
              f"{', '.join(f'{p:.1f}' for p in peaks)} MB ({max(peaks) / peak:.3f} of the tool's), "
              f"{summary['tiles']} tiles, the map {'identical' if same else 'DIFFERS'}")
    driver = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(f"  2 workers / 1 worker: {results[2] / results[1]:.2f} (goal <= 0.6); one worker / the "
          f"tool: {results[1] / seconds:.2f} (goal <= 1.25); driver peak {driver:.1f} MB "
          f"({driver / peak:.3f} of the tool's; goal <= 0.10)")
    stereo = pathlib.Path(args.data) / "orbslam2_stereo_keyframes"
    if stereo.is_dir():
        rating_share(args.tool, stereo, out)


if __name__ == "__main__":
    main()
