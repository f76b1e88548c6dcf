"""A drop-in for trimesh's ray intersectors (``trimesh.ray.ray_triangle`` and
``trimesh.ray.ray_pyembree``): the same methods, arguments and return shapes, answered by a baked
field. trimesh is not needed to use it; any object with ``vertices`` (V, 3) and ``faces`` (F, 3)
works as the mesh.

>>> import trimesh, vlf.trimesh
>>> mesh = trimesh.creation.icosphere()
>>> mesh.ray = vlf.trimesh.RayMeshIntersector(mesh)   # every mesh.ray.* call now uses the field
>>> index_tri, index_ray = mesh.ray.intersects_id([[0, 0, -5]], [[0, 0, 1]])

The mesh is baked on first use, through the bake cache (``cache_dir``, default
:func:`vlf.default_cache_dir`): a later run on the same mesh copies the field from the cache
instead of baking it again. A mesh that changes is baked again (trimesh tracks changes to its
meshes; of another object, replaced ``vertices`` or ``faces`` arrays are noticed).

Differences from trimesh's own intersectors, all on the side of exactness: hits are found by a
watertight test (a ray through an edge shared by two faces hits at least one of them), every hit
along a ray is found directly rather than by re-casting from offset origins, and with
``multiple_hits`` a ray's hits are listed in order of distance, ray after ray (trimesh's Embree
intersector lists first hits of every ray, then second hits, ...). Faces of zero area are never
hit; of several faces with exactly the same vertices, one is reported.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

import vlf

__all__ = ["RayMeshIntersector"]

# trimesh's default direction for contains_points.
_CONTAINS_DIRECTION = np.array([0.4395064455, 0.617598629942, 0.652231566745])


class RayMeshIntersector:
    """Ray queries on ``mesh`` through a baked field. ``bake_options`` are those of
    :func:`vlf.bake_arrays` (``directions``, ``tiles``, ``cache_dir``, ``no_cache``, ``threads``,
    ...); ``threads`` also applies to the queries."""

    def __init__(self, mesh: Any, **bake_options: Any):
        self.mesh = mesh
        self._options = dict(bake_options)
        self._threads = self._options.get("threads")
        self._field: Optional[vlf.Field] = None
        self._face: Optional[np.ndarray] = None
        self._key: Optional[tuple] = None

    def _mesh_key(self) -> tuple:
        """What tells a changed mesh: a trimesh mesh's hash of its contents (cached by trimesh
        until the mesh changes, so cheap to ask every query), else the identity and shape of the
        arrays (a plain object whose arrays are replaced)."""
        if type(self.mesh).__hash__ not in (None, object.__hash__):
            try:
                return ("contents", hash(self.mesh))
            except TypeError:
                pass
        v, f = self.mesh.vertices, self.mesh.faces
        return ("arrays", id(v), id(f), np.shape(v), np.shape(f))

    @property
    def field(self) -> vlf.Field:
        """The mesh's field, baked (or copied from the cache) on first use and again whenever the
        mesh's vertices or faces change."""
        key = self._mesh_key()
        if self._field is None or key != self._key:
            options = vlf._shim_options(self._options, len(self.mesh.faces))
            self._field = vlf.bake_arrays(self.mesh.vertices, self.mesh.faces, name="trimesh", **options)
            self._face = self._field.source_indices()
            self._key = key
        return self._field

    def _faces(self, triangle_id: np.ndarray) -> np.ndarray:
        """Mesh face indices of field triangle ids (-1 stays -1), once :attr:`field` is baked."""
        out = np.full(triangle_id.shape, -1, dtype=np.int64)
        hit = triangle_id >= 0
        out[hit] = self._face[triangle_id[hit]]
        return out

    @staticmethod
    def _rays(ray_origins: Any, ray_directions: Any):
        o = np.array(ray_origins, dtype=np.float64)
        d = np.array(ray_directions, dtype=np.float64)
        if o.shape != d.shape:
            raise ValueError("Ray origin and direction don't match!")
        return o.reshape((-1, 3)), d.reshape((-1, 3))

    def intersects_id(
        self,
        ray_origins: Any,
        ray_directions: Any,
        multiple_hits: bool = True,
        max_hits: int = 100,
        return_locations: bool = False,
    ):
        """The faces hit by each ray: ``(index_tri, index_ray)``, and ``locations`` (m, 3) if
        ``return_locations``. With ``multiple_hits``, every hit along each ray (at most
        ``max_hits`` per ray, the closest ones), ray after ray in order of distance; otherwise
        the first hit of each ray that hits."""
        o, d = self._rays(ray_origins, ray_directions)
        field = self.field
        if multiple_hits:
            lists = field.all_hits(o, d, max_hits=max(int(max_hits), 0), threads=self._threads)
            index_ray = lists.ray_ids
            t = lists.t.astype(np.float64)
            index_tri = self._faces(lists.triangle_id)
        else:
            hits = field.closest_hits(o, d, threads=self._threads)
            index_ray = np.flatnonzero(hits.triangle_id >= 0).astype(np.int64)
            t = hits.t[index_ray].astype(np.float64)
            index_tri = self._faces(hits.triangle_id[index_ray])
        if return_locations:
            locations = o[index_ray] + t[:, None] * d[index_ray]
            return index_tri, index_ray, locations
        return index_tri, index_ray

    def intersects_location(self, ray_origins: Any, ray_directions: Any, multiple_hits: bool = True):
        """Where rays hit the mesh: ``(locations (m, 3), index_ray (m,), index_tri (m,))``."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins: Any, ray_directions: Any) -> np.ndarray:
        """(n,) int64: the face each ray hits first, -1 if none."""
        o, d = self._rays(ray_origins, ray_directions)
        hits = self.field.closest_hits(o, d, threads=self._threads)
        return self._faces(hits.triangle_id)

    def intersects_any(self, ray_origins: Any, ray_directions: Any) -> np.ndarray:
        """(n,) bool: whether each ray hits the mesh."""
        o, d = self._rays(ray_origins, ray_directions)
        return self.field.any_hits(o, d, threads=self._threads)

    def contains_points(self, points: Any, check_direction: Optional[Any] = None) -> np.ndarray:
        """(n,) bool: whether each point is inside the mesh, by the parity of the crossings of a
        ray each way along ``check_direction`` (trimesh's test, with each face counted once).
        Undefined for points on the surface."""
        points = np.asanyarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError("points must be (n,3)")
        contains = np.zeros(len(points), dtype=bool)
        lo, hi = self.field.bounds
        inside = np.logical_and(points >= lo, points <= hi).all(axis=1)
        if not inside.any():
            return contains
        direction = _CONTAINS_DIRECTION if check_direction is None else np.asarray(check_direction, dtype=np.float64).reshape(3)
        p = points[inside]
        forward = self.field.hit_counts(p, direction, threads=self._threads)
        backward = self.field.hit_counts(p, -direction, threads=self._threads)
        odd_f, odd_b = forward % 2 == 1, backward % 2 == 1
        agree = odd_f == odd_b
        mask = inside.copy()
        mask[mask] = agree
        contains[mask] = odd_f[agree]
        # Disagreement where neither way is free space: try once more in another direction.
        broken = ~agree & (forward > 0) & (backward > 0)
        if broken.any() and check_direction is None:
            rng = np.random.default_rng(len(points))
            again = rng.random(3) - 0.5
            mask = inside.copy()
            mask[mask] = broken
            contains[mask] = self.contains_points(p[broken], check_direction=again / np.linalg.norm(again))
        return contains
