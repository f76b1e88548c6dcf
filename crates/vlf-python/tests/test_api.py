"""Shapes, dtypes, strides, threads, errors, opening, metadata, baking, the GIL, and leaks."""

import gc
import os
import threading
import time

import numpy as np
import pytest

import vlf
from conftest import FIXTURES, SMALL, random_soup
from reference import random_rays


@pytest.fixture(scope="module")
def rays(soup):
    v, f, field = soup
    return random_rays(field.bounds, 4000, 3)


def same(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a, b))


def test_dtypes_strides_and_layouts_give_the_same_answers(soup, rays):
    v, f, field = soup
    o, d = rays
    want = field.closest_hits(o, d)
    wide = np.zeros((len(o), 7))
    wide[:, 2:5] = d
    variants = [
        (o.astype(np.float64), d.astype(np.float64)),  # exact in f32: the same rays
        (np.asfortranarray(o), np.asfortranarray(d)),
        (o, wide[:, 2:5]),  # a strided view
        (o.astype(">f4"), d.astype(">f8")),  # big-endian
        (list(map(list, o)), d),  # lists
    ]
    for oo, dd in variants:
        assert same(field.closest_hits(oo, dd), want)
    strided = np.repeat(o, 2, axis=0)[::2]
    assert not strided.flags.c_contiguous
    assert same(field.closest_hits(strided, d), want)
    # One origin for every ray, integers converted.
    one = field.all_hits([0, 0, 0], d)
    assert np.array_equal(one.counts, field.hit_counts(np.zeros_like(d), d))
    ints = field.hit_counts(np.zeros((5, 3), dtype=np.int32), np.array([[1, 0, 0]] * 5, dtype=np.int64))
    assert ints.shape == (5,)
    # A single ray.
    assert field.closest_hits(o[0], d[0]).t.shape == (1,)
    # No rays.
    empty = field.all_hits(np.zeros((0, 3)), np.zeros((0, 3)))
    assert empty.ray_splits.tolist() == [0] and field.closest_hits(np.zeros((0, 3)), np.zeros((0, 3))).t.shape == (0,)


def test_threads_give_the_same_answers(soup, rays):
    v, f, field = soup
    o, d = rays
    for query in (field.closest_hits, field.all_hits):
        base = query(o, d, threads=1)
        for t in (None, 0, 2, 3):
            assert same(query(o, d, threads=t), base)
    assert np.array_equal(field.hit_counts(o, d, threads=1), field.hit_counts(o, d, threads=2))
    assert np.array_equal(field.any_hits(o, d, threads=1), field.any_hits(o, d, threads=2))
    with pytest.raises(ValueError, match="threads"):
        field.closest_hits(o, d, threads=-1)
    with pytest.raises(ValueError, match="over the limit"):
        field.closest_hits(o, d, threads=5000)


def test_bad_rays_raise_clear_errors(soup):
    v, f, field = soup
    o = np.zeros((4, 3), dtype=np.float32)
    d = np.tile(np.float32([0, 0, 1]), (4, 1))
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        field.closest_hits(np.zeros((4, 2)), d)
    with pytest.raises(ValueError, match="one origin per direction"):
        field.closest_hits(o[:3], d)
    with pytest.raises(ValueError, match="tmin"):
        field.closest_hits(o, d, tmin=np.zeros(3))
    bad = o.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="ray 2: the origin"):
        field.closest_hits(bad, d)
    zero = d.copy()
    zero[3] = 0
    with pytest.raises(ValueError, match="ray 3: the direction is zero"):
        field.any_hits(o, zero)
    inf = d.copy()
    inf[1, 0] = np.inf
    with pytest.raises(ValueError, match="ray 1: the direction"):
        field.all_hits(o, inf)
    with pytest.raises(ValueError, match="greater than tmax"):
        field.hit_counts(o, d, tmin=2.0, tmax=1.0)
    with pytest.raises(ValueError, match="NaN"):
        field.hit_counts(o, d, tmax=np.nan)
    with pytest.raises(ValueError, match="max_hits"):
        field.all_hits(o, d, max_hits=-1)
    with pytest.raises(TypeError):
        field.closest_hits(np.array([["a", "b", "c"]]), d[:1])
    huge = np.full((1, 3), 1e300)
    with pytest.raises(ValueError, match="not finite"):
        field.closest_hits(huge, d[:1])


def test_open_from_path_and_bytes_and_metadata(tmp_path):
    v, f = random_soup(200, 9)
    path = tmp_path / "soup.vlf"
    baked = vlf.bake_arrays(v, f, path, name="soup", **SMALL)
    assert baked.path == str(path) and path.is_file()
    a = vlf.open(path)
    b = vlf.open(path.read_bytes())
    c = vlf.Field.open(str(path))
    o, d = random_rays(a.bounds, 500, 1)
    assert same(a.closest_hits(o, d), b.closest_hits(o, d)) and same(a.all_hits(o, d), c.all_hits(o, d))
    assert a.triangle_count == b.triangle_count == 200
    assert a.content_hash == b.content_hash == baked.content_hash and len(a.content_hash) == 64
    assert len(a.input_hash) == 64 and a.input_hash != a.content_hash
    np.testing.assert_allclose(a.bounds, [v.min(axis=0), v.max(axis=0)], atol=1e-6)
    center, radius = a.bounding_sphere
    assert np.all(np.linalg.norm(v - center, axis=1) <= radius * (1 + 1e-6))
    p = a.parameters
    assert p["directions"] > 0 and p["tiles"] == 16 and p["requested_tiles"] == 16 and p["leaf_size"] >= 1
    assert a.format_version[0] >= 1 and a.size_bytes == path.stat().st_size and not a.is_packed
    prov = a.provenance(0)
    assert prov["input"] == "soup" and prov["kind"] == "program" and 0 <= prov["index"] < 200
    assert a.provenance(10**6) is None and a.provenance(-1) is None
    idx = a.source_indices()
    assert sorted(idx.tolist()) == list(range(200))
    np.testing.assert_allclose(a.triangles(), v[f][idx], atol=1e-6)
    assert "200 triangles" in repr(a) and b.path is None


def test_bad_fields_and_files_raise(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.vlf"):
        vlf.open(tmp_path / "missing.vlf")
    junk = tmp_path / "junk.vlf"
    junk.write_bytes(b"not a field at all" * 10)
    with pytest.raises(vlf.FieldError):
        vlf.open(junk)
    with pytest.raises(vlf.FieldError):
        vlf.open(b"")
    v, f = random_soup(50, 2)
    good = vlf.bake_arrays(v, f, tmp_path / "good.vlf", **SMALL)
    data = bytearray((tmp_path / "good.vlf").read_bytes())
    data[0] ^= 0xFF
    with pytest.raises(vlf.FieldError):
        vlf.open(bytes(data))
    data[0] ^= 0xFF
    with pytest.raises(vlf.FieldError):
        vlf.open(bytes(data[: len(data) // 3]))
    assert issubclass(vlf.FieldError, ValueError) and good.triangle_count == 50


def test_bake_errors(tmp_path):
    v, f = random_soup(10, 1)
    with pytest.raises(ValueError, match="out of range"):
        vlf.bake_arrays(v, f + 100, **SMALL)
    with pytest.raises(ValueError, match=r"shape \(F, 3\)"):
        vlf.bake_arrays(v, f[:, :2], **SMALL)
    with pytest.raises(ValueError, match=r"shape \(V, 3\)"):
        vlf.bake_arrays(v[:, :2], f, **SMALL)
    with pytest.raises(ValueError, match="whole vertex indices"):
        vlf.bake_arrays(v, f + 0.5, **SMALL)
    bad = v.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        vlf.bake_arrays(bad, f, **SMALL)
    with pytest.raises(ValueError, match="no triangles"):
        vlf.bake_arrays(np.zeros((3, 3)), [[0, 1, 2]], **SMALL)
    with pytest.raises(TypeError, match="unknown bake option"):
        vlf.bake_arrays(v, f, directoins=9)
    with pytest.raises(ValueError):
        vlf.bake_arrays(v, f, directions=0, no_cache=True)
    with pytest.raises(FileNotFoundError, match="nowhere.obj"):
        vlf.bake(tmp_path / "nowhere.obj", tmp_path / "x.vlf", **SMALL)
    broken = tmp_path / "broken.obj"
    broken.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(vlf.BakeError, match="out of range"):
        vlf.bake(broken, tmp_path / "x.vlf", **SMALL)
    # Float and unsigned dtypes are accepted.
    ok = vlf.bake_arrays(v.astype(np.float32), f.astype(np.uint16).astype(np.float64), **SMALL)
    assert ok.triangle_count == 10


def test_bake_files_through_the_cache(tmp_path, cache_dir):
    bunny = FIXTURES / "bunny.obj"
    opts = dict(directions=33, tiles=16, cache_dir=cache_dir, threads=2)
    first = vlf.bake(bunny, tmp_path / "a.vlf", **opts)
    assert first.bake_info["cache"] == "miss" and first.provenance(0)["input"] == "bunny.obj"
    second = vlf.bake([bunny], tmp_path / "b.vlf", **opts)
    assert second.bake_info["cache"] == "hit" and second.content_hash == first.content_hash
    third = vlf.bake(str(bunny), tmp_path / "c.vlf", directions=33, tiles=16, no_cache=True)
    assert third.bake_info["cache"] == "disabled" and third.content_hash == first.content_hash
    # Arrays: the same through the cache.
    v, f = random_soup(300, 4)
    a = vlf.bake_arrays(v, f, cache_dir=cache_dir, directions=33, tiles=16)
    b = vlf.bake_arrays(v, f, cache_dir=cache_dir, directions=33, tiles=16)
    assert (a.bake_info["cache"], b.bake_info["cache"]) == ("miss", "hit") and a.content_hash == b.content_hash
    assert len(list((cache_dir / "v1").glob("*.vlf"))) == 2


def test_the_gil_is_released_during_queries(soup):
    v, f, field = soup
    o, d = random_rays(field.bounds, 400_000, 8)
    counter = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            counter[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        time.sleep(0.05)
        start = time.perf_counter()
        before = counter[0]
        field.all_hits(o, d, threads=1)
        after = counter[0]
        took = time.perf_counter() - start
    finally:
        stop.set()
        t.join()
    # The other thread ran throughout the query (with the GIL held it could not run at all).
    assert took > 0.05 and after - before > 10_000, (took, after - before)


def test_no_leak_over_a_long_loop(soup):
    v, f, field = soup
    o, d = random_rays(field.bounds, 2000, 9)

    def rss():
        with open("/proc/self/statm") as s:
            return int(s.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

    if not os.path.exists("/proc/self/statm"):
        pytest.skip("needs /proc")
    for _ in range(20):
        field.all_hits(o, d)
    gc.collect()
    base = rss()
    for _ in range(400):
        field.closest_hits(o, d)
        field.all_hits(o, d, max_hits=3)
        field.hit_counts(o, d)
        field.any_hits(o, d)
        try:
            field.closest_hits(o[:1] * np.nan, d[:1])
        except ValueError:
            pass
    gc.collect()
    grown = rss() - base
    assert grown < 8 << 20, f"resident memory grew by {grown} bytes"


def test_views_into_packed_records_are_read_right(soup, rays):
    # A field of a packed structured array is not aligned to its values: read in place, it was
    # read at the wrong offsets. The wrapper copies it; the native module refuses it.
    v, f, field = soup
    o, d = rays
    n = len(o)
    want = field.closest_hits(o, d, tmin=np.linspace(0, 1, n, dtype=np.float32))
    rec = np.zeros(n, dtype=[("tag", "u1"), ("o", "<f4", (3,)), ("d", "<f8", (3,)), ("tmin", "<f4")])
    rec["o"], rec["d"], rec["tmin"] = o, d, np.linspace(0, 1, n, dtype=np.float32)
    assert not rec["o"].flags.aligned and not rec["tmin"].flags.aligned
    assert same(field.closest_hits(rec["o"], rec["d"], tmin=rec["tmin"]), want)
    tmax = np.full(n, np.inf, dtype=np.float32)
    with pytest.raises(ValueError, match="not aligned"):
        field._inner.closest(rec["o"], d, rec["tmin"], tmax)


def test_a_batch_too_large_for_memory_is_a_memory_error(soup):
    v, f, field = soup
    o = np.broadcast_to(np.zeros(3), (10**13, 3))  # no memory of its own
    for query in (field.closest_hits, field.any_hits, field.hit_counts):
        with pytest.raises(MemoryError, match="smaller batches"):
            query(o, [0, 0, 1.0])


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="counts threads in /proc")
def test_many_thread_counts_do_not_pile_up_threads(soup, rays):
    v, f, field = soup
    o, d = rays
    before = len(os.listdir("/proc/self/task"))
    for k in range(2, 40):
        field.any_hits(o[:100], d[:100], threads=k)
    # The every-core pool and the last sized pool at most (a dropped pool's threads end soon).
    deadline = time.time() + 10
    while len(os.listdir("/proc/self/task")) > before + 39 + os.cpu_count() and time.time() < deadline:
        time.sleep(0.05)
    assert len(os.listdir("/proc/self/task")) <= before + 39 + os.cpu_count()


def test_errors_pickle_and_name_their_package():
    import pickle

    for error in (vlf.FieldError("bad bytes"), vlf.BakeError("bad mesh")):
        back = pickle.loads(pickle.dumps(error))
        assert type(back) is type(error) and back.args == error.args
        assert type(error).__module__ == "vlf"


def test_a_directory_or_a_pipe_is_refused_at_once(tmp_path):
    with pytest.raises(IsADirectoryError, match="is a directory"):
        vlf.open(tmp_path)
    if hasattr(os, "mkfifo"):
        fifo = tmp_path / "pipe.vlf"
        os.mkfifo(fifo)
        with pytest.raises(OSError, match="not a regular file"):
            vlf.open(fifo)


def test_a_hit_past_the_largest_float_is_no_hit(soup):
    # A direction so short that every hit lies past the largest float32: no hit (it was reported
    # at t = inf, on whichever triangle had the lower id).
    v, f, field = soup
    c, r = field.bounding_sphere
    target = np.asarray(v)[np.asarray(f)[0]].mean(axis=0)
    o = np.array([[target[0], target[1], c[2] + 3 * r]])
    dist = o[0, 2] - target[2]
    for length, hit in ((dist / 1e39, False), (1.0, True)):  # the hit at t = 1e39, then at t = dist
        d = np.array([[0.0, 0.0, -length]])
        h = field.closest_hits(o, d)
        assert (h.triangle_id[0] >= 0) == hit and np.isfinite(h.t[0]) == hit
        assert field.any_hits(o, d)[0] == hit and (field.hit_counts(o, d)[0] > 0) == hit


def test_bytes_paths_are_paths(tmp_path):
    v, f = random_soup(20, 5)
    out = os.fsencode(tmp_path / "b.vlf")
    field = vlf.bake_arrays(v, f, out, **SMALL)
    assert field.path == os.fsdecode(out)
    assert vlf.Field.open(out).triangle_count == field.triangle_count


@pytest.mark.skipif(not os.path.isfile("/proc/self/status"), reason="reads the address space used from /proc")
def test_all_hits_beyond_memory_is_a_memory_error_not_an_abort(tmp_path):
    # A stack of 500 parallel squares (1,000 triangles): every ray down through it hits one
    # triangle of each, so 20,000 rays hold 10 million hits (about 400 MB of results). Under an
    # address-space limit that leaves about 200 MB, the batch must stop with a MemoryError, not
    # abort the interpreter.
    layers = 500
    z = np.repeat(np.linspace(0.0, 1.0, layers), 4)
    xy = np.tile([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]], (layers, 1))
    v = np.column_stack([xy, z])
    quads = np.arange(4 * layers).reshape(layers, 4)
    f = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    path = tmp_path / "stack.vlf"
    vlf.bake_arrays(v, f, path, **SMALL)
    script = f"""
import resource, sys
import numpy as np
import vlf
field = vlf.open({str(path)!r})
rng = np.random.default_rng(1)
o = np.column_stack([rng.uniform(-0.9, 0.9, (20000, 2)), np.full(20000, 2.0)])
d = np.tile([0.0, 0.0, -1.0], (20000, 1))
assert field.all_hits(o[:10], d[:10]).counts.tolist() == [{layers}] * 10
used = int(next(l for l in open("/proc/self/status") if l.startswith("VmSize:")).split()[1]) * 1024
resource.setrlimit(resource.RLIMIT_AS, (used + (200 << 20), resource.RLIM_INFINITY))
try:
    field.all_hits(o, d)
except MemoryError as e:
    print("MemoryError:", e)
    sys.exit(0)
sys.exit("no MemoryError")
"""
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, (run.returncode, run.stdout, run.stderr[-2000:])
    assert "20000 rays" in run.stdout and "ulimit -v" in run.stdout and "max_hits" in run.stdout, run.stdout
