"""No Python call, pickle or state crashes the interpreter: every class refuses use before
__init__, pickles without their state make objects that refuse use, OccupancyMap.__setstate__
validates all it loads (a fuzz of random and mutated states and pickles), and the module's
smaller promises (errno subclasses, memory_limit values, membership, MemoryError)."""

import copyreg
import errno
import io
import math
import pickle
import random
import struct
import zlib

import numpy as np
import pytest

from conftest import random_scan


def classes(knnocc):
    return [knnocc.OccupancyMap, knnocc.Mapper, knnocc.LiveMapper, knnocc.Sequence,
            knnocc.Knn2022FirstPass]


ARGUMENT_SETS = [(), (0,), (np.zeros((4, 3)),), ((0, 0, 0), np.zeros((4, 3))), ("all",)]


def assert_refused(call):
    with pytest.raises(TypeError) as e:
        call()
    return str(e.value)


CHECKED_DUNDERS = ("__len__", "__getitem__", "__contains__", "__getstate__", "__eq__",
                   "__repr__")


# A use of each class that takes no arguments.
FIRST_USE = {"OccupancyMap": len, "Mapper": lambda o: o.model, "LiveMapper": len, "Sequence": len,
             "Knn2022FirstPass": lambda o: o.mu}


def assert_unusable(obj):
    """An object made without __init__: its first use names the cause, and every method and
    property raises TypeError (the cause, or arguments that do not fit) without running."""
    cls = type(obj)
    message = assert_refused(lambda: FIRST_USE[cls.__name__](obj))
    assert "knnocc." + cls.__name__ + ": " in message and "without __init__" in message
    for use in (lambda: len(obj), lambda: 0 in obj, lambda: obj[0]):
        with pytest.raises(TypeError):
            use()
    for name in dir(cls):
        if name.startswith("__") and (name not in CHECKED_DUNDERS or name not in vars(cls)):
            continue
        attr = getattr(cls, name)
        if isinstance(attr, property):
            assert "without __init__" in assert_refused(lambda: getattr(obj, name))
        elif callable(attr):
            # An operator given the wrong number of arguments answers NotImplemented.
            for args in ((obj,), (0,)) if name == "__eq__" else ARGUMENT_SETS:
                with pytest.raises(TypeError):
                    getattr(obj, name)(*args)


def test_every_class_refuses_use_before_init(knnocc):
    for cls in classes(knnocc):
        obj = cls.__new__(cls)
        assert_unusable(obj)
        del obj  # dropping one is safe

        class Sub(cls):
            pass

        assert "without __init__" in assert_refused(
            lambda: FIRST_USE[cls.__name__](Sub.__new__(Sub)))
    # A thread guard is never consulted on an object that holds nothing.
    m = knnocc.OccupancyMap.__new__(knnocc.OccupancyMap)
    for call in (lambda: m.insert_point_cloud(np.zeros((1, 3)), (0, 0, 0)),
                 lambda: m.occupancy_at([[0, 0, 0]]), lambda: knnocc.cast_ray(m, (0, 0, 0),
                                                                                (1, 0, 0))):
        assert "without __init__" in assert_refused(call)
    good = knnocc.OccupancyMap(0.1)
    assert "without __init__" in assert_refused(lambda: good == m)


def forged_pickle(cls, protocol, *state):
    """The bytes of a pickle that makes a `cls` with cls.__new__ (copyreg.__newobj__) and then
    gives it `state` if one is given: the form pickle.dumps writes for these classes."""

    class Proxy:
        @property
        def __class__(self):  # what the pickler checks __newobj__'s class against
            return cls

        def __reduce__(self):
            return (copyreg.__newobj__, (cls,)) + state

    return pickle.dumps(Proxy(), protocol=protocol)


def test_pickles_without_state_give_objects_that_refuse_use(knnocc):
    for cls in classes(knnocc):
        for protocol in (2, 4, 5):
            obj = pickle.loads(forged_pickle(cls, protocol))
            assert type(obj) is cls
            assert_unusable(obj)
        # The hand-written 30-byte form: GLOBAL, EMPTY_TUPLE, NEWOBJ, STOP.
        raw = b"\x80\x02cknnocc\n" + cls.__name__.encode() + b"\n)\x81."
        assert "without __init__" in assert_refused(
            lambda: FIRST_USE[cls.__name__](pickle.loads(raw)))
    for obj in (knnocc.Mapper(0.1), knnocc.LiveMapper(0.1), knnocc.Knn2022FirstPass()):
        with pytest.raises(TypeError, match="cannot pickle"):
            pickle.dumps(obj)


def sample_map(knnocc):
    m = knnocc.OccupancyMap(0.1, prob_hit=0.8, prob_miss=0.3)
    m.insert_point_cloud(random_scan(5, n=3000), (0, 0, 0))
    m.memory_limit = 10**9
    return m


def with_voxels(state, keys, values, count=None, crc=None):
    """`state` with new voxel bytes, the count and CRC made to match unless given."""
    s = list(state)
    s[8] = len(values) // 4 if count is None else count
    s[9], s[10] = keys, values
    s[11] = zlib.crc32(values, zlib.crc32(keys)) if crc is None else crc
    return tuple(s)


def load(knnocc, state):
    m = knnocc.OccupancyMap.__new__(knnocc.OccupancyMap)
    m.__setstate__(state)
    return m


def test_setstate_refuses_each_damage_and_names_it(knnocc):
    m = sample_map(knnocc)
    state = m.__getstate__()
    assert state[0] == 2 and state[8] == len(m) and len(state) == 12
    assert load(knnocc, state) == m
    keys, values = state[9], state[10]
    n = len(m)
    nan_at_3 = values[:12] + struct.pack("<f", math.nan) + values[16:]
    dup = keys[:6] + keys[:6] + keys[12:]  # voxel 1's key is voxel 0's
    inf_res = tuple(math.inf if i == 1 else v for i, v in enumerate(state))
    cases = {
        "not a tuple": [list(state), None, 7, {}],
        "state version": [(), state[:11], (3,) + state[1:], (True,) + state[1:],
                          (1,) + state[1:], ("2",) + state[1:]],
        "resolution must be a number": [(2, "0.1") + state[2:]],
        "resolution must be finite": [inf_res, (2, 10**400) + state[2:]],
        "prob_hit must be finite": [(2, 0.1, 10**400) + state[3:]],
        "resolution": [(2, -0.1) + state[2:], (2, 0.0) + state[2:]],
        "hit probability": [(2, 0.1, 0.4) + state[3:]],
        "miss probability": [(2, 0.1, 0.8, 0.6) + state[4:]],
        "clamp_min must be smaller": [state[:4] + (3.0, -2.0) + state[6:]],
        "occupancy_threshold must lie": [state[:6] + (9.0,) + state[7:]],
        "memory_limit must be a non-negative integer": [
            state[:7] + (-5,) + state[8:], state[:7] + (1.5,) + state[8:],
            state[:7] + (None,) + state[8:]],
        r"memory_limit must be below 2\*\*64": [state[:7] + (2**70,) + state[8:]],
        "must be bytes": [state[:9] + ("x" * len(keys),) + state[10:],
                          state[:10] + (bytearray(values),) + state[11:]],
        "cut short or damaged": [with_voxels(state, keys[: 3 * n], values[: 2 * n], count=n),
                                 with_voxels(state, keys, values, count=n + 1),
                                 with_voxels(state, keys[:-1], values)],
        "CRC-32": [with_voxels(state, keys, values, crc=state[11] ^ 1),
                   with_voxels(state, keys, values, crc=str(state[11])),
                   with_voxels(state, keys[:6] + bytes([keys[6] ^ 1]) + keys[7:], values,
                               crc=state[11])],
        "not finite": [with_voxels(state, keys, nan_at_3)],
        "appear twice": [with_voxels(state, dup, values)],
    }
    for expected, states in cases.items():
        for s in states:
            with pytest.raises(ValueError, match=expected):
                load(knnocc, s)
    # A count whose byte sizes wrap round 2^64 to the bytes given (2^63 + k voxels of 4 and 6
    # bytes: 4k and 6k modulo 2^64) is not k voxels.
    for k in (0, 1, n):
        for count in (2**63 + k, 2**62 + k):
            with pytest.raises(ValueError, match="cut short or damaged"):
                load(knnocc, with_voxels(state, keys[: 6 * k], values[: 4 * k], count=count))
    # A consistent state cut to half its voxels is a smaller map, not half of this one.
    half = load(knnocc, with_voxels(state, keys[: 6 * (n // 2)], values[: 4 * (n // 2)]))
    assert len(half) == n // 2
    # The version 1 states of earlier releases still load.
    v1 = (1,) + state[1:8] + (keys, values)
    assert load(knnocc, v1) == m
    with pytest.raises(ValueError, match="not finite"):
        load(knnocc, (1,) + state[1:8] + (keys, nan_at_3))


MUTANTS = [None, -5, 0, 1, 2, 2**62, 2**63, 2**63 + 1, 2**64 - 1, 2**64, 2**70, -(2**70), 10**400,
           math.nan, math.inf, -math.inf, 1e300, 0.5, 1.5, True, "x", b"", b"\x00" * 6, (), [], {},
           object()]


def mutate(state, rng):
    s = list(state)
    if not s:
        return (rng.choice(MUTANTS),)
    whole = len(s) == 12 and isinstance(s[9], bytes) and isinstance(s[10], bytes) and s[10]
    kind = rng.randrange(6) if whole else rng.choice((0, 5))
    if kind == 0:  # one field replaced
        s[rng.randrange(len(s))] = rng.choice(MUTANTS)
    elif kind == 1:  # a byte of the voxels changed, the CRC left as it was
        i = rng.choice((9, 10))
        if s[i]:
            b = bytearray(s[i])
            b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)
            s[i] = bytes(b)
    elif kind == 2:  # cut short, count and CRC as they were
        i = rng.choice((9, 10))
        s[i] = s[i][: rng.randrange(len(s[i]) + 1)]
    elif kind == 3:  # a random log-odds, everything else made consistent
        b = bytearray(s[10])
        at = 4 * rng.randrange(len(b) // 4)
        b[at:at + 4] = struct.pack("<f", rng.choice([math.nan, math.inf, -math.inf, 1e38, -3.0,
                                                     0.0]))
        return with_voxels(s, s[9], bytes(b))
    elif kind == 4:  # random keys, consistent
        keys = bytes(rng.getrandbits(8) for _ in range(len(s[9])))
        return with_voxels(s, keys, s[10])
    else:  # items dropped or added
        return tuple(s[: rng.randrange(len(s))]) if rng.random() < 0.5 else tuple(s) + (0,)
    return tuple(s)


def test_fuzz_states_and_pickles(knnocc, tmp_path):
    """Random and mutated states, directly and through pickle.loads: each is refused with
    ValueError or TypeError, or loads a valid map (finite log-odds, its count of voxels, a file
    that reads back equal)."""
    rng = random.Random(20261208)
    m = knnocc.OccupancyMap(0.2)
    m.insert_point_cloud(random_scan(6, n=400, extent=1.0), (0, 0, 0))
    state = m.__getstate__()
    accepted = 0
    for i in range(1500):
        s = mutate(state, rng)
        if rng.random() < 0.3:
            s = mutate(s, rng)
        through_pickle = rng.random() < 0.5
        try:
            if through_pickle:

                loaded = pickle.loads(forged_pickle(knnocc.OccupancyMap, 4, s))
            else:
                loaded = load(knnocc, s)
        except (ValueError, TypeError):
            continue
        except pickle.PicklingError:
            continue
        accepted += 1
        _, values = loaded.voxels()
        assert np.isfinite(values).all()
        assert len(loaded) == (s[8] if len(s) == 12 else len(s[9]) // 6)
        if accepted <= 20:
            loaded.write(tmp_path / "f.ot")
            assert knnocc.read_map(tmp_path / "f.ot") == loaded
    assert 0 < accepted < 1500


class KnnoccOnly(pickle.Unpickler):
    """Resolves only what a knnocc pickle needs, so mutated bytes cannot name other callables."""

    def find_class(self, module, name):
        if (module, name) in {("knnocc", "OccupancyMap"), ("copyreg", "__newobj__"),
                              ("copyreg", "_reconstructor"), ("builtins", "object")}:
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"{module}.{name} is not allowed")


def test_fuzz_pickle_bytes(knnocc):
    rng = random.Random(7)
    m = knnocc.OccupancyMap(0.2)
    m.insert_point_cloud(random_scan(7, n=300, extent=1.0), (0, 0, 0))
    blob = pickle.dumps(m, protocol=4)
    loaded_ok = 0
    for _ in range(3000):
        b = bytearray(blob)
        for _ in range(rng.randrange(1, 4)):
            b[rng.randrange(len(b))] = rng.randrange(256)
        if rng.random() < 0.2:
            b = b[: rng.randrange(len(b))]
        try:
            obj = KnnoccOnly(io.BytesIO(bytes(b))).load()
        except Exception:  # any clean Python error: the interpreter lives on
            continue
        if isinstance(obj, knnocc.OccupancyMap):
            try:
                len(obj)
            except TypeError:
                continue
            loaded_ok += 1
            assert np.isfinite(obj.voxels()[1]).all()
    assert loaded_ok > 0  # flips in the pickle's framing that change nothing still load


def test_errors_carry_errno_and_the_os_subclass(knnocc, tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        knnocc.read_map(tmp_path / "missing.bt")
    assert isinstance(e.value, knnocc.Error) and e.value.errno == errno.ENOENT
    assert str(e.value) == str(tmp_path / "missing.bt") + ": cannot open: No such file or directory"
    assert type(e.value) is knnocc.Error.FileNotFoundError
    again = pickle.loads(pickle.dumps(e.value))
    assert type(again) is type(e.value) and again.errno == errno.ENOENT
    assert str(again) == str(e.value) and again.filename == e.value.filename
    (tmp_path / "folder.ply").mkdir()
    with pytest.raises(IsADirectoryError):
        knnocc.read_points(tmp_path / "folder.ply")
    with pytest.raises(FileNotFoundError):
        knnocc.read_points(tmp_path / "missing.ply")
    bad = tmp_path / "bad.bt"
    bad.write_bytes(b"not a map\n")
    with pytest.raises(knnocc.Error) as e:
        knnocc.read_map(bad)
    assert type(e.value) is knnocc.Error and e.value.errno is None
    assert str(e.value).startswith(str(bad) + ": ")


def test_memory_limit_values(knnocc):
    for obj in (knnocc.OccupancyMap(0.1), knnocc.Mapper(0.1), knnocc.LiveMapper(0.1)):
        for bad, kind in ((-5, ValueError), (2**64, ValueError), (1.5, TypeError),
                          ("1", TypeError), (None, TypeError), (True, TypeError)):
            with pytest.raises(kind, match="memory_limit"):
                obj.memory_limit = bad
        obj.memory_limit = 2**64 - 1
        assert obj.memory_limit == 2**64 - 1
        obj.memory_limit = 0


def test_membership_and_inputs(knnocc):
    live = knnocc.LiveMapper(0.1)
    live.add(3, np.eye(4), np.ones((2, 3)))
    assert 3 in live and 4 not in live
    for x in (2**70, 2**64, -1, -(2**70), "x", 3.0, None):
        assert (x in live) is False
    mapper = knnocc.Mapper(0.1, model="robust")
    big = [[2**70, 0, 0], [1, 1, 1]]
    with pytest.raises(ValueError, match=r"evidence must be in \[0, 2\^32 - 1\]"):
        mapper.insert_keyframe((0, 0, 0), np.ones((2, 3)), [1, 2], big)
    with pytest.raises(ValueError, match=r"evidence must be in \[0, 2\^32 - 1\]"):
        mapper.insert_keyframe((0, 0, 0), np.ones((2, 3)), [1, 2], [[-1, 0, 0], [1, 1, 1]])
    with pytest.raises(ValueError, match="ids must be map-point ids"):
        mapper.insert_keyframe((0, 0, 0), np.ones((2, 3)), [2**70, 1])
    # A zero-stride view of 10^12 points needs a copy numpy cannot make: MemoryError, as
    # documented, not a complaint about the shape.
    huge = np.lib.stride_tricks.as_strided(np.zeros(3), shape=(10**12, 3), strides=(0, 8))
    m = knnocc.OccupancyMap(0.1)
    with pytest.raises(MemoryError):
        m.insert_point_cloud(huge, (0, 0, 0))
    assert len(m) == 0
    # Under a memory limit, a copy that would pass it is refused before numpy makes it.
    view = np.lib.stride_tricks.as_strided(np.ones(3), shape=(10**8, 3), strides=(0, 8))
    live = knnocc.LiveMapper(0.1)
    for obj, insert in ((m, lambda: m.insert_point_cloud(view, (0, 0, 0))),
                        (mapper, lambda: mapper.insert_keyframe((0, 0, 0), view)),
                        (live, lambda: live.add(0, np.eye(4), view))):
        obj.memory_limit = 10**7
        with pytest.raises(MemoryError, match="2400.0* MB, more than the memory limit"):
            insert()
        assert len(obj.map if obj is not m else m) == 0
    m.insert_point_cloud(np.ones((1000, 3)), (0, 0, 0))  # read in place: no copy to refuse
    assert len(m) > 0


def test_an_empty_cloud_that_declares_ids_has_ids(knnocc, tmp_path):
    """Ids belong to the format: a PLY of zero points with an id property gives an empty id
    array, one without gives None."""
    header = "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n" \
             "property float z\n"
    (tmp_path / "ids.ply").write_text(header + "property uint id\nend_header\n")
    (tmp_path / "plain.ply").write_text(header + "end_header\n")
    points, ids = knnocc.read_points(tmp_path / "ids.ply")
    assert points.shape == (0, 3) and ids is not None and ids.shape == (0,)
    assert ids.dtype == np.uint64
    assert knnocc.read_points(tmp_path / "plain.ply")[1] is None
