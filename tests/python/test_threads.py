"""The GIL and the one-writer rule. The module releases the GIL while the library works and
guards each object: one writer, or readers while no writer runs; a call that would break this
raises RuntimeError. A guard is held from before the GIL is released until after it is taken
back, so a thread that runs Python code and finds an object refused has caught the object's user
inside the library without the GIL. The tests look for such witnesses (a long call is made longer
until one is seen); they assert no timings."""

import os
import threading

import numpy as np
import pytest

from conftest import random_scan


def refused(call):
    """True when `call` is refused because another thread is in the object."""
    try:
        call()
    except RuntimeError as e:
        assert "another thread" in str(e) and "refused" in str(e), str(e)
        return True
    return False


def while_running(make_long_call, watch, tries=4):
    """Runs make_long_call(scale)() in a thread, with scale 1, 4, 16, 64, and calls watch()
    repeatedly while it runs, until watch() returns True (the witness); returns whether it did.
    The long calls are sized so that scale 64 stays within about 100 MB."""
    scale = 1
    for _ in range(tries):
        call = make_long_call(scale)
        done, errors = threading.Event(), []

        def run():
            try:
                call()
            except BaseException as e:  # re-raised below
                errors.append(e)
            finally:
                done.set()

        t = threading.Thread(target=run)
        t.start()
        seen = False
        while not seen and not done.is_set():
            seen = watch()
        t.join()
        if errors:
            raise errors[0]
        if seen:
            return True
        scale *= 4
    return False


def long_insert(m, scale):
    points = random_scan(1, n=50000 * scale, extent=10.0)
    return lambda: m.insert_point_cloud(points, (0, 0, 0))


def test_two_threads_insert_into_two_maps_at_once(knnocc):
    map1, map2 = knnocc.OccupancyMap(0.1), knnocc.OccupancyMap(0.1)
    small = random_scan(2, n=2000)
    stop = threading.Event()

    def keep_inserting():  # thread B: short insertions into map2 until told to stop
        while not stop.is_set():
            map2.insert_point_cloud(small, (0, 0, 0))

    b = threading.Thread(target=keep_inserting)
    b.start()
    try:
        # map1 busy, map2 busy, map1 busy again: thread A's one call into map1 spans the three
        # probes, so at the second both threads were inside the library.
        both = while_running(lambda s: long_insert(map1, s),
                             lambda: refused(lambda: len(map1)) and refused(lambda: len(map2))
                             and refused(lambda: len(map1)))
    finally:
        stop.set()
        b.join()
    assert both
    assert len(map1) > 0 and len(map2) > 0


def test_one_writer_per_object(knnocc):
    m = knnocc.OccupancyMap(0.1)
    small = random_scan(3, n=100)
    seen = []

    def second_writer():
        if refused(lambda: m.insert_point_cloud(small, (0, 0, 0))):
            seen.append("write")
            return refused(lambda: m.occupancy_at(small)) and refused(lambda: m.to_bytes())
        return False

    assert while_running(lambda s: long_insert(m, s), second_writer)
    m.insert_point_cloud(small, (0, 0, 0))  # free again
    assert m.occupancy_at(small).shape == (100,)


def test_queries_share_the_object_and_keep_writers_out(knnocc):
    m = knnocc.OccupancyMap(0.05)
    m.insert_point_cloud(random_scan(4), (0, 0, 0))
    mine = random_scan(5, n=1000)
    expect = m.occupancy_at(mine)

    def long_query(scale):
        points = random_scan(6, n=100000 * scale, extent=4.0)
        return lambda: m.occupancy_at(points)

    def witness():  # a writer refused, this thread's query served, a writer refused again
        return (refused(lambda: setattr(m, "memory_limit", 0))
                and np.array_equal(m.occupancy_at(mine), expect)
                and refused(lambda: m.insert_point_cloud(mine, (0, 0, 0))))

    assert while_running(long_query, witness)


def test_ray_casts_release_the_gil(knnocc):
    m = knnocc.OccupancyMap(0.05)
    m.insert_point_cloud(random_scan(7, n=1000), (0, 0, 0))

    def long_casts(scale):
        directions = np.random.default_rng(8).normal(size=(5000 * scale, 3))
        return lambda: m.cast_ray((0, 0, 0), directions, max_range=10.0, ignore_unknown=True)

    assert while_running(long_casts, lambda: refused(lambda: setattr(m, "memory_limit", 0)))


def test_mapper_and_its_map_have_one_writer(knnocc):
    for model in ("octomap", "knn"):
        mapper = knnocc.Mapper(0.1, model=model)
        small = random_scan(9, n=100).astype(np.float64)

        def long_keyframe(scale):
            points = random_scan(10, n=(50000 if model == "octomap" else 5000) * scale,
                                 extent=10.0 if model == "octomap" else 3.0)
            ids = np.arange(len(points)) + scale * 10**7 if model == "knn" else None
            return lambda: mapper.insert_keyframe((0, 0, 0), points, ids)

        def witness():
            ids = np.arange(100) if model == "knn" else None
            return (refused(lambda: mapper.insert_keyframe((0, 0, 0), small, ids))
                    and refused(lambda: mapper.map.occupancy_at(small))
                    and refused(lambda: mapper.statistics()))

        assert while_running(long_keyframe, witness), model
        assert len(mapper.map) > 0


def test_live_mapper_has_one_writer(knnocc):
    live = knnocc.LiveMapper(0.1)
    live.add(0, np.eye(4), random_scan(11, n=100))
    keyframes = iter(range(1, 100))

    def long_add(scale):
        points = random_scan(12, n=50000 * scale, extent=10.0)
        return lambda: live.add(next(keyframes), np.eye(4), points)

    assert while_running(long_add, lambda: refused(lambda: live.repose({0: np.eye(4)}))
                         and refused(lambda: len(live)))


def test_file_output_releases_the_gil(knnocc, tmp_path):
    # Writing to a FIFO blocks until a reader opens it: the write returns only if this thread,
    # which needs the GIL, reads the bytes while the other thread is inside the library.
    fifo = tmp_path / "map.bt"
    os.mkfifo(fifo)
    m = knnocc.OccupancyMap(0.1)
    m.insert_point_cloud(random_scan(13), (0, 0, 0))
    writer = threading.Thread(target=m.write, args=(fifo,))
    writer.start()
    with open(fifo, "rb") as f:
        got = f.read()
    writer.join()
    assert got == m.to_bytes("bt")


def test_many_threads_on_one_object_never_crash(knnocc):
    m = knnocc.OccupancyMap(0.1)
    scans = [random_scan(20 + i, n=3000) for i in range(8)]
    done, refusals, errors = [], [], []

    def worker(i):
        for j in range(40):
            try:
                if (i + j) % 3 == 0:
                    m.insert_point_cloud(scans[(i + j) % 8], (0, 0, 0))
                    done.append(1)
                else:
                    m.occupancy_at(scans[i])
                    len(m)
            except RuntimeError:
                refusals.append(1)
            except BaseException as e:
                errors.append(e)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and len(done) > 0
    assert len(m) == sum(m.count_voxels())
