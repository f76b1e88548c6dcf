"""Every query against the float64 brute force (tests/reference.py) over the field's own stored
triangles, on a random triangle soup and on the bunny: zero differences away from edges; hits that
graze an edge (float precision decides) are counted apart and must be few."""

import numpy as np
import pytest

from reference import brute_force, grazing_rays, per_ray_sets, random_rays

MESHES = ["soup", "bunny"]


def setup(request, name, n=3000, seed=1):
    v, f, field = request.getfixturevalue(name)
    o, d = random_rays(field.bounds, n, seed)
    tris = field.triangles()
    ref = brute_force(tris, o, d)
    return field, tris, o, d, ref


@pytest.mark.parametrize("name", MESHES)
def test_closest_hits_match_the_brute_force(request, name):
    field, tris, o, d, ref = setup(request, name)
    n = len(o)
    hits = field.closest_hits(o, d)
    assert hits.t.shape == (n,) and hits.t.dtype == np.float32
    assert hits.triangle_id.shape == (n,) and hits.triangle_id.dtype == np.int64
    assert hits.uv.shape == (n, 2) and hits.normal.shape == (n, 3)
    graze = grazing_rays(ref, n)
    first = np.full(n, -1)
    first_t = np.full(n, np.inf)
    seen = np.zeros(n, dtype=bool)
    for r, f, t in zip(ref["ray"], ref["tri"], ref["t"]):
        if not seen[r]:
            seen[r], first[r], first_t[r] = True, f, t
    ok = ~graze
    assert ok.sum() > 0.95 * n
    assert np.array_equal(hits.triangle_id[ok] >= 0, first[ok] >= 0)
    hit = ok & (first >= 0)
    assert hit.sum() > n // 5
    np.testing.assert_allclose(hits.t[hit], first_t[hit], rtol=1e-5, atol=1e-6)
    # Another triangle only at the same distance (coincident faces).
    other = hit & (hits.triangle_id != first)
    np.testing.assert_allclose(hits.t[other], first_t[other], rtol=1e-6)
    # Barycentrics rebuild the hit point; normals are the triangle's unit normals.
    h = hits.triangle_id >= 0
    tri = tris[hits.triangle_id[h]]
    u, v = hits.uv[h, 0:1].astype(np.float64), hits.uv[h, 1:2].astype(np.float64)
    p = (1 - u - v) * tri[:, 0] + u * tri[:, 1] + v * tri[:, 2]
    q = o[h].astype(np.float64) + hits.t[h, None].astype(np.float64) * d[h]
    scale = np.abs(field.bounds).max()
    np.testing.assert_allclose(p, q, atol=1e-4 * scale)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    np.testing.assert_allclose(hits.normal[h], nrm, atol=1e-5)
    assert np.array_equal(hits.barycentric[:, 1:], hits.uv)
    miss = ~h
    assert np.all(np.isinf(hits.t[miss])) and np.all(hits.normal[miss] == 0)


@pytest.mark.parametrize("name", MESHES)
def test_any_hits_all_hits_and_counts_match_the_brute_force(request, name):
    field, tris, o, d, ref = setup(request, name, seed=2)
    n = len(o)
    graze = grazing_rays(ref, n)
    want = per_ray_sets(ref["ray"], ref["tri"], n)
    lists = field.all_hits(o, d)
    got = per_ray_sets(lists.ray_ids, lists.triangle_id, n)
    counts = field.hit_counts(o, d)
    anyhit = field.any_hits(o, d)
    assert anyhit.dtype == bool and counts.dtype == np.int64
    assert lists.ray_splits.shape == (n + 1,) and lists.ray_splits[0] == 0
    mismatches = [i for i in range(n) if not graze[i] and got[i] != want[i]]
    assert mismatches == [], f"{len(mismatches)} rays differ, e.g. {mismatches[:5]}"
    assert np.array_equal(counts, lists.counts)
    assert np.array_equal(anyhit, counts > 0)
    several = int((counts > 1).sum())
    assert several > n // 20, several
    # Each triangle once per ray, in order of t then id, the t of the brute force.
    for i in range(n):
        r = lists.ray(i)
        assert len(set(r.triangle_id.tolist())) == len(r.triangle_id)
        assert np.all(np.diff(r.t) >= 0)
    tf = dict(((int(a), int(b)), t) for a, b, t in zip(ref["ray"], ref["tri"], ref["t"]))
    for a, b, t in zip(lists.ray_ids, lists.triangle_id, lists.t):
        if (int(a), int(b)) in tf:
            assert abs(t - tf[(int(a), int(b))]) <= 1e-5 * max(1.0, abs(t))
    # The first hit is the closest hit's distance; a maximum keeps the closest hits.
    closest = field.closest_hits(o, d)
    firsts = lists.ray_splits[:-1][counts > 0]
    assert np.array_equal(lists.t[firsts], closest.t[counts > 0])
    for k in (1, 2, 5):
        capped = field.all_hits(o, d, max_hits=k)
        assert np.array_equal(capped.counts, np.minimum(counts, k))
        for i in np.flatnonzero(counts > 0)[:500]:
            a, b = capped.ray(i), lists.ray(i)
            assert np.array_equal(a.triangle_id, b.triangle_id[:k]) and np.array_equal(a.t, b.t[:k])
    none = field.all_hits(o, d, max_hits=0)
    assert len(none.t) == 0 and np.all(none.ray_splits == 0)


def test_grazing_hits_are_rare(request):
    field, tris, o, d, ref = setup(request, "soup", seed=5)
    assert grazing_rays(ref, len(o)).sum() < 0.02 * len(o)


def test_intervals_scalar_and_per_ray(soup):
    v, f, field = soup
    o, d = random_rays(field.bounds, 2000, 7)
    full = field.all_hits(o, d)
    rng = np.random.default_rng(0)
    tmin = rng.random(len(o)).astype(np.float32) * 0.5
    tmax = tmin + rng.random(len(o)).astype(np.float32) * 2.0
    part = field.all_hits(o, d, tmin, tmax)
    for i in range(len(o)):
        a, b = full.ray(i), part.ray(i)
        keep = (a.t >= tmin[i]) & (a.t <= tmax[i])
        assert np.array_equal(a.triangle_id[keep], b.triangle_id), i
    c = field.hit_counts(o, d, 0.25, 1.0)
    assert np.array_equal(c, [((full.ray(i).t >= 0.25) & (full.ray(i).t <= 1.0)).sum() for i in range(len(o))])
    hits = field.closest_hits(o, d, tmin, tmax)
    first = np.array([b.t[0] if len(b.t) else np.inf for b in (part.ray(i) for i in range(len(o)))])
    assert np.array_equal(hits.t, first.astype(np.float32))
    assert np.array_equal(field.any_hits(o, d, tmin, tmax), part.counts > 0)


def test_against_trimeshs_pure_numpy_intersector(bunny):
    trimesh = pytest.importorskip("trimesh")
    from trimesh.ray.ray_triangle import RayMeshIntersector as Numpy

    v, f, field = bunny
    tris = field.triangles()
    mesh = trimesh.Trimesh(tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3), process=False)
    o, d = random_rays(field.bounds, 1500, 11)
    ref = Numpy(mesh)
    graze = grazing_rays(brute_force(tris, o, d), len(o))
    ok = ~graze
    first = ref.intersects_first(o, d)
    got = field.closest_hits(o, d).triangle_id
    # trimesh's first hit may be another face at the same distance; compare distances there.
    differ = ok & (first != got)
    assert differ.sum() <= 0.002 * len(o), np.flatnonzero(differ)[:10]
    assert np.array_equal(ref.intersects_any(o, d)[ok], field.any_hits(o, d)[ok])
    tri, ray = ref.intersects_id(o, d, multiple_hits=True)
    want = per_ray_sets(ray, tri, len(o))
    lists = field.all_hits(o, d)
    have = per_ray_sets(lists.ray_ids, lists.triangle_id, len(o))
    bad = [i for i in range(len(o)) if ok[i] and want[i] != have[i]]
    assert bad == []
