#!/usr/bin/env python3
"""The Python module against the C++ library, in the same run (the issue's goals; printed, not
asserted). From the repository root, after building knnocc_python and bench_python_ref:

    PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py [--rounds 7] [--data DIR]

1. insertion: the 10 TUM fr2/pioneer_slam2 clouds at 0.05 m, world-frame float32 arrays passed to
   OccupancyMap.insert_point_cloud, against build/bin/bench_python_ref making the same calls on
   ScanInserter (one thread each); rounds alternate between the two, medians compared, and the
   two maps (.ot bytes) must be equal. Goal: Python <= 1.05x C++.
2. occupancy_at on 10^6 points drawn uniformly in the TUM map's box (float64, one call, one
   thread), against the same points queried one by one in C++; the results must agree.
   Goal: >= 20 M points/s.
3. import time: `import knnocc` in a fresh interpreter (the module imports numpy at its first
   numpy call, not at import), and `import knnocc, numpy` for what a script pays. Goal: <= 0.2 s.
"""

import argparse
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import knnocc

ROOT = pathlib.Path(__file__).resolve().parents[1]


def median(values):
    return statistics.median(values)


def timed(call):
    """(wall-clock seconds, CPU seconds of this process) of call()."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = call()
    return time.perf_counter() - wall, time.process_time() - cpu, result


def import_seconds(code, runs=9):
    """Median seconds of the statement `code` in fresh interpreters (start-up not counted)."""
    probe = f"import time; t = time.perf_counter(); {code}; print(time.perf_counter() - t)"
    env = dict(os.environ, PYTHONPATH=str(pathlib.Path(knnocc.__file__).parent))
    return statistics.median(
        float(subprocess.run([sys.executable, "-c", probe], env=env, check=True,
                             capture_output=True, text=True).stdout) for _ in range(runs))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--data", default=str(ROOT.parent / "shared" / "data"))
    args = parser.parse_args()
    build = pathlib.Path(knnocc.__file__).resolve().parents[1]
    ref = build / "bin" / "bench_python_ref"
    tum = pathlib.Path(args.data) / "tum_fr2_pioneer_slam2"
    if not ref.exists() or not tum.is_dir():
        sys.exit(f"needs {ref} (cmake --build build --target bench_python_ref) and {tum}")
    print(f"knnocc {knnocc.__version__} module {knnocc.__file__}, Python {sys.version.split()[0]}, "
          f"numpy {np.__version__}; C++: {ref}")

    clouds = [(knnocc.to_world(pose, points).astype(np.float32), pose[:3, 3])
              for pose, points, _ in knnocc.read_sequence(tum)]
    n_points = sum(len(c) for c, _ in clouds)
    first = knnocc.OccupancyMap(0.05)
    for world, origin in clouds:
        first.insert_point_cloud(world, origin)
    centres, _ = first.voxels()
    rng = np.random.default_rng(1)
    queries = rng.uniform(centres.min(0), centres.max(0), size=(10**6, 3))

    # times[side][what] = [(wall, cpu) per round]
    times = {side: {"insert": [], "query": []} for side in ("python", "c++")}
    same_map = same_queries = True
    with tempfile.TemporaryDirectory() as tmp:
        query_file, out = os.path.join(tmp, "queries.f64"), os.path.join(tmp, "ref")
        queries.tofile(query_file)
        for _ in range(args.rounds):
            f = subprocess.run([ref, tum, "0.05", query_file, out], check=True,
                               capture_output=True, text=True).stdout.split()
            times["c++"]["insert"].append((float(f[1]), float(f[5])))
            times["c++"]["query"].append((float(f[3]), float(f[7])))

            def insert():
                m = knnocc.OccupancyMap(0.05)
                for world, origin in clouds:
                    m.insert_point_cloud(world, origin)
                return m

            wall, cpu, m = timed(insert)
            times["python"]["insert"].append((wall, cpu))
            wall, cpu, occupancy = timed(lambda: m.occupancy_at(queries))
            times["python"]["query"].append((wall, cpu))
            same_map &= m.to_bytes("ot") == pathlib.Path(out + ".ot").read_bytes()
            same_queries &= np.array_equal(occupancy, np.fromfile(out + ".occ", np.int8))

    def med(side, what, clock):  # median seconds over the rounds; clock 0 wall, 1 CPU
        return median([t[clock] for t in times[side][what]])

    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} hardware threads (the "
          f"wall clock also counts other processes' turns; CPU time does not)")
    print(f"\n1. insertion, TUM fr2/pioneer_slam2: {len(clouds)} clouds, {n_points} points, "
          f"0.05 m, one thread, {args.rounds} rounds alternating, medians")
    for clock, name in ((0, "wall clock"), (1, "CPU time  ")):
        py, cpp = med("python", "insert", clock), med("c++", "insert", clock)
        print(f"   {name}: Python OccupancyMap.insert_point_cloud {py:.4f} s, C++ "
              f"ScanInserter::insert_point_cloud {cpp:.4f} s, ratio {py / cpp:.3f} "
              f"(goal <= 1.05: {'met' if py / cpp <= 1.05 else 'NOT met'})")
    print(f"   same map (.ot bytes) every round: {'yes' if same_map else 'NO'}")
    print(f"\n2. occupancy_at, 10^6 points uniform in the map's box ({int(np.sum(occupancy >= 0))} "
          f"in known voxels), float64, one call, one thread, medians")
    for clock, name in ((0, "wall clock"), (1, "CPU time  ")):
        py, cpp = 1 / med("python", "query", clock), 1 / med("c++", "query", clock)
        print(f"   {name}: Python occupancy_at {py:.1f} M points/s, C++ loop of coord_to_key + "
              f"is_occupied {cpp:.1f} M points/s (goal >= 20: {'met' if py >= 20 else 'NOT met'})")
    print(f"   same results as C++ every round: {'yes' if same_queries else 'NO'}")
    alone, with_numpy = import_seconds("import knnocc"), import_seconds("import knnocc, numpy")
    print("\n3. import time (median of 9 fresh interpreters)")
    print(f"   import knnocc {alone:.3f} s, import knnocc, numpy {with_numpy:.3f} s "
          f"(goal <= 0.2 s: {'met' if alone <= 0.2 else 'NOT met'})")
    return 0 if same_map and same_queries else 1


if __name__ == "__main__":
    sys.exit(main())
