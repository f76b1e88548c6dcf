"""The shims against the libraries they stand in for, on the same rays: trimesh's own
intersectors (pure numpy, and Embree through embreex where it installs) and Open3D's
RaycastingScene (where it installs). Rays that graze an edge are left out of exact comparisons."""

import numpy as np
import pytest

import vlf
import vlf.open3d
import vlf.trimesh
from conftest import SMALL, load_obj, FIXTURES
from reference import brute_force, grazing_rays, per_ray_sets, random_rays


class Mesh:
    """What the trimesh shim needs of a mesh, without trimesh."""

    def __init__(self, vertices, faces):
        self.vertices, self.faces = vertices, faces


@pytest.fixture(scope="module")
def bunny_mesh():
    v, f = load_obj(FIXTURES / "bunny.obj")
    return Mesh(v, f)


def exact_rays(mesh, n, seed):
    tris = np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)]
    bounds = np.array([tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)])
    o, d = random_rays(bounds, n, seed)
    return o, d, ~grazing_rays(brute_force(tris, o, d), n)


def test_trimesh_shim_without_trimesh(bunny_mesh):
    r = vlf.trimesh.RayMeshIntersector(bunny_mesh, **SMALL)
    o, d, ok = exact_rays(bunny_mesh, 1500, 1)
    tris = np.asarray(bunny_mesh.vertices)[bunny_mesh.faces]
    ref = brute_force(tris, o, d)
    want = per_ray_sets(ref["ray"], ref["tri"], len(o))
    index_tri, index_ray = r.intersects_id(o, d)
    assert index_tri.dtype == np.int64 and index_ray.dtype == np.int64 and index_tri.shape == index_ray.shape
    have = per_ray_sets(index_ray, index_tri, len(o))
    assert [i for i in range(len(o)) if ok[i] and have[i] != want[i]] == []
    first = r.intersects_first(o, d)
    assert first.shape == (len(o),) and first.dtype == np.int64
    nearest = np.full(len(o), -1)
    seen = set()
    for ray, tri in zip(ref["ray"], ref["tri"]):
        if ray not in seen:
            seen.add(ray)
            nearest[ray] = tri
    assert np.array_equal(first[ok] >= 0, nearest[ok] >= 0)
    assert (first[ok] != nearest[ok]).sum() <= 2
    assert np.array_equal(r.intersects_any(o, d), first >= 0)
    locations, lray, ltri = r.intersects_location(o, d)
    assert locations.shape == (len(lray), 3) and np.array_equal(ltri, index_tri)
    # Locations lie on their faces' planes.
    t = tris[ltri]
    nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    assert np.abs(np.einsum("ij,ij->i", locations - t[:, 0], nrm)).max() < 1e-4
    # max_hits keeps the closest; multiple_hits=False the first.
    one_tri, one_ray = r.intersects_id(o, d, multiple_hits=False)
    assert np.array_equal(one_ray, np.flatnonzero(first >= 0)) and np.array_equal(one_tri, first[first >= 0])
    capped_tri, capped_ray = r.intersects_id(o, d, max_hits=2)
    assert np.bincount(capped_ray, minlength=len(o)).max() <= 2


def test_trimesh_shim_rebakes_when_the_mesh_changes():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    m = Mesh(v, np.array([[0, 1, 2]]))
    r = vlf.trimesh.RayMeshIntersector(m, directions=9, tiles=4, no_cache=True)
    assert r.intersects_any([[0.2, 0.2, 1]], [[0, 0, -1]]).tolist() == [True]
    m.vertices = v + [5, 0, 0]
    assert r.intersects_any([[0.2, 0.2, 1]], [[0, 0, -1]]).tolist() == [False]


def test_trimesh_shim_against_trimesh():
    trimesh = pytest.importorskip("trimesh")
    from trimesh.ray.ray_triangle import RayMeshIntersector as Numpy

    mesh = trimesh.creation.icosphere(subdivisions=3)
    mesh.vertices = mesh.vertices + [0.1, -0.2, 0.3]
    ours = vlf.trimesh.RayMeshIntersector(mesh, **SMALL)
    refs = [Numpy(mesh)]
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector as Embree

        refs.append(Embree(mesh))
    except ImportError:
        pass
    o, d, ok = exact_rays(mesh, 2000, 4)
    for ref in refs:
        a, b = ref.intersects_first(o, d), ours.intersects_first(o, d)
        assert a.shape == b.shape and (a[ok] != b[ok]).sum() <= 2, type(ref)
        assert np.array_equal(ref.intersects_any(o, d)[ok], ours.intersects_any(o, d)[ok])
        rt, rr = ref.intersects_id(o, d, multiple_hits=True)
        ot, orr = ours.intersects_id(o, d, multiple_hits=True)
        want, have = per_ray_sets(rr, rt, len(o)), per_ray_sets(orr, ot, len(o))
        bad = [i for i in range(len(o)) if ok[i] and want[i] != have[i]]
        assert len(bad) <= 0.002 * len(o), (type(ref), bad[:5])
        rl, rray, rtri = ref.intersects_location(o, d)
        ol, oray, otri = ours.intersects_location(o, d)
        assert rl.shape[1] == ol.shape[1] == 3 and rray.dtype.kind == oray.dtype.kind == "i"
        # The first location of each ray that hits agrees.
        first_ref = {int(r): rl[k] for k, r in reversed(list(enumerate(rray)))}
        for k, r in enumerate(oray[np.r_[True, oray[1:] != oray[:-1]]][:200]):
            if ok[r] and int(r) in first_ref:
                pos = ol[np.flatnonzero(oray == r)[0]]
                dist = np.linalg.norm(ol[oray == r] - first_ref[int(r)], axis=1).min()
                assert dist < 1e-4, (r, pos, first_ref[int(r)])
    # contains_points, against trimesh's (its default intersector) on points off the surface.
    rng = np.random.default_rng(0)
    pts = rng.random((3000, 3)) * 2.6 - 1.3 + [0.1, -0.2, 0.3]
    r = np.linalg.norm(pts - [0.1, -0.2, 0.3], axis=1)
    pts = pts[np.abs(r - 1.0) > 0.02]
    assert np.array_equal(ours.contains_points(pts), mesh.contains(pts))
    assert np.array_equal(ours.contains_points(pts), r[np.abs(r - 1.0) > 0.02] < 0.99)


@pytest.fixture(scope="module")
def o3d():
    return pytest.importorskip("open3d")


def two_meshes():
    v1, f1 = load_obj(FIXTURES / "bunny.obj")
    rng = np.random.default_rng(2)
    v2 = (rng.random((600, 3)) - 0.5) * 0.1 + v1.mean(axis=0)
    f2 = np.arange(600).reshape(-1, 3)
    return [(v1.astype(np.float32), f1.astype(np.uint32)), (v2.astype(np.float32), f2.astype(np.uint32))]


def test_open3d_shim_without_open3d():
    scene = vlf.open3d.RaycastingScene(**SMALL)
    meshes = two_meshes()
    assert [scene.add_triangles(v, f) for v, f in meshes] == [0, 1]
    allv = np.concatenate([m[0] for m in meshes]).astype(np.float64)
    tris = np.concatenate([meshes[0][0][meshes[0][1]], meshes[1][0][meshes[1][1]]]).astype(np.float64)
    bounds = np.array([allv.min(0), allv.max(0)])
    o, d = random_rays(bounds, 1200, 3)
    rays = np.hstack((o, d)).reshape(40, 30, 6)
    ans = scene.cast_rays(rays)
    assert ans["t_hit"].shape == (40, 30) and ans["primitive_uvs"].shape == (40, 30, 2)
    assert ans["primitive_normals"].shape == (40, 30, 3) and ans["geometry_ids"].dtype == np.uint32
    assert isinstance(ans["t_hit"].numpy(), np.ndarray)
    ref = brute_force(tris, o, d)
    ok = ~grazing_rays(ref, len(o))
    n0 = len(meshes[0][1])
    geo = ans["geometry_ids"].reshape(-1)
    prim = ans["primitive_ids"].reshape(-1)
    flat = np.where(geo == 1, prim.astype(np.int64) + n0, prim.astype(np.int64))
    flat[geo == scene.INVALID_ID] = -1
    first = {}
    for r, f in zip(ref["ray"], ref["tri"]):
        first.setdefault(int(r), int(f))
    want = np.array([first.get(i, -1) for i in range(len(o))])
    assert (flat[ok] != want[ok]).sum() <= 2
    assert np.all(ans["t_hit"].reshape(-1)[flat < 0] == np.inf)
    count = scene.count_intersections(rays)
    assert count.shape == (40, 30) and count.dtype == np.int32
    lx = scene.list_intersections(rays)
    assert lx["ray_splits"].shape == (1201,) and lx["ray_splits"].dtype == np.uint32
    assert np.array_equal(np.diff(lx["ray_splits"].astype(np.int64)), count.reshape(-1))
    occl = scene.test_occlusions(rays)
    assert np.array_equal(occl, count > 0)
    near = scene.test_occlusions(rays, tnear=0.0, tfar=1e-9)
    assert near.sum() <= 2
    with pytest.raises(ValueError, match=r"\(\.\.\., 6\)"):
        scene.cast_rays(np.zeros((4, 5), dtype=np.float32))
    with pytest.raises(ValueError, match="empty"):
        vlf.open3d.RaycastingScene().cast_rays(rays)


def test_open3d_shim_against_open3d(o3d):
    meshes = two_meshes()
    theirs = o3d.t.geometry.RaycastingScene()
    ours = vlf.open3d.RaycastingScene(**SMALL)
    for v, f in meshes:
        assert theirs.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f)) == ours.add_triangles(v, f)
    tris = np.concatenate([v[f] for v, f in meshes]).astype(np.float64)
    allv = np.concatenate([m[0] for m in meshes]).astype(np.float64)
    o, d = random_rays(np.array([allv.min(0), allv.max(0)]), 2000, 6)
    ok = ~grazing_rays(brute_force(tris, o, d), len(o))
    rays = np.hstack((o, d)).astype(np.float32)
    a = {k: v.numpy() for k, v in theirs.cast_rays(o3d.core.Tensor(rays)).items()}
    b = ours.cast_rays(rays)
    assert set(a) == set(b)
    for k in a:
        assert a[k].shape == b[k].shape and a[k].dtype == b[k].dtype, k
    assert (a["primitive_ids"][ok] != b["primitive_ids"][ok]).sum() <= 2
    assert np.array_equal(a["geometry_ids"][ok], b["geometry_ids"][ok])
    same = ok & (a["primitive_ids"] == b["primitive_ids"]) & (a["primitive_ids"] != ours.INVALID_ID)
    np.testing.assert_allclose(a["t_hit"][same], b["t_hit"][same], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(a["primitive_uvs"][same], b["primitive_uvs"][same], atol=1e-3)
    np.testing.assert_allclose(a["primitive_normals"][same], b["primitive_normals"][same], atol=1e-4)
    miss = a["primitive_ids"] == ours.INVALID_ID
    assert np.all(np.isinf(b["t_hit"][miss & ok]))
    occ_a = theirs.test_occlusions(o3d.core.Tensor(rays)).numpy()
    assert np.array_equal(occ_a[ok], ours.test_occlusions(rays)[ok])
    occ_a = theirs.test_occlusions(o3d.core.Tensor(rays), tnear=0.1, tfar=0.8).numpy()
    assert np.array_equal(occ_a[ok], ours.test_occlusions(rays, tnear=0.1, tfar=0.8)[ok])
    ca = theirs.count_intersections(o3d.core.Tensor(rays)).numpy()
    cb = ours.count_intersections(rays)
    assert ca.dtype == cb.dtype and (ca[ok] != cb[ok]).sum() <= 2
    la = {k: v.numpy() for k, v in theirs.list_intersections(o3d.core.Tensor(rays)).items()}
    lb = ours.list_intersections(rays)
    assert set(la) == set(lb)
    for k in la:
        assert la[k].dtype == lb[k].dtype and la[k].shape[1:] == lb[k].shape[1:], k
    key = lambda lx: per_ray_sets(lx["ray_ids"].astype(np.int64), lx["geometry_ids"].astype(np.int64) * 10**6 + lx["primitive_ids"], len(o))
    sa, sb = key(la), key(lb)
    assert sum(1 for i in range(len(o)) if ok[i] and sa[i] != sb[i]) <= 2


def test_shims_bake_tiny_meshes_with_the_default_options():
    # A mesh of one triangle bakes with the library's defaults (at least 4 MiB for any mesh),
    # through the shims and directly.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    scene = vlf.open3d.RaycastingScene()
    scene.add_triangles(v, np.array([[0, 1, 2]], dtype=np.uint32))
    ans = scene.cast_rays(np.array([[0.2, 0.2, 1, 0, 0, -1]], dtype=np.float32))
    assert ans["t_hit"].tolist() == [1.0] and ans["primitive_ids"].tolist() == [0]
    assert scene.field.bake_info["cache"] in ("miss", "hit")
    r = vlf.trimesh.RayMeshIntersector(Mesh(v, np.array([[0, 1, 2]])))
    assert r.intersects_first([[0.2, 0.2, 1]], [[0, 0, -1]]).tolist() == [0]
    field = vlf.bake_arrays(v, [[0, 1, 2]], no_cache=True)
    assert field.triangle_count == 1
    assert field.parameters["max_bytes_per_triangle"] == 1024


def test_trimesh_shim_notices_changes_to_a_trimesh_mesh():
    trimesh = pytest.importorskip("trimesh")
    mesh = trimesh.creation.box()
    r = vlf.trimesh.RayMeshIntersector(mesh, directions=9, tiles=4, no_cache=True)
    assert r.intersects_any([[0, 0, 5]], [[0, 0, -1]]).tolist() == [True]
    first = r.field
    assert r.field is first  # no change, no bake
    mesh.apply_translation([10, 0, 0])
    assert r.intersects_any([[0, 0, 5]], [[0, 0, -1]]).tolist() == [False]
    assert r.field is not first
