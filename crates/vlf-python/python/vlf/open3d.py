"""A drop-in for Open3D's ``open3d.t.geometry.RaycastingScene``: the same methods, arguments and
result keys, answered by a baked field, with numpy arrays in and out. Open3D is not needed to use
it; its tensors and meshes are accepted where Open3D accepts them.

>>> import numpy as np, vlf.open3d
>>> scene = vlf.open3d.RaycastingScene()
>>> vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
>>> scene.add_triangles(vertices, np.array([[0, 1, 2]], dtype=np.uint32))
0
>>> ans = scene.cast_rays(np.array([[0.2, 0.2, 1, 0, 0, -1]], dtype=np.float32))
>>> float(ans["t_hit"][0]), int(ans["primitive_ids"][0])
(1.0, 0)

The geometries added are baked into one field on the first query after an addition, through the
bake cache (``cache_dir``, default :func:`vlf.default_cache_dir`). Results are numpy arrays of
Open3D's dtypes and shapes; they also have Open3D's ``.numpy()`` method (returning the array
itself), so code written for Open3D's tensors runs unchanged. Hits come from a watertight test;
``count_intersections`` counts each triangle once; ``list_intersections`` lists each ray's hits
in order of distance.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

import vlf

__all__ = ["RaycastingScene"]

INVALID_ID = 4294967295


class _Array(np.ndarray):
    """A numpy array with Open3D tensors' ``.numpy()``."""

    def numpy(self) -> np.ndarray:
        return self.view(np.ndarray)


def _out(a: np.ndarray) -> _Array:
    return np.asarray(a).view(_Array)


def _numpy(x: Any) -> np.ndarray:
    """An Open3D tensor (or anything with ``.numpy()``) or array-like as a numpy array."""
    if hasattr(x, "numpy") and not isinstance(x, np.ndarray):
        return x.numpy()
    return np.asarray(x)


class RaycastingScene:
    """A scene of triangle meshes for ray casting. ``nthreads``: threads for the bake (0 for
    every core); ``device`` is accepted for Open3D's signature and must be a CPU device if given.
    ``bake_options`` are those of :func:`vlf.bake_arrays`."""

    INVALID_ID = INVALID_ID

    def __init__(self, nthreads: int = 0, device: Any = None, **bake_options: Any):
        if device is not None and "CPU" not in str(device).upper():
            raise ValueError(f"vlf.open3d.RaycastingScene runs on the CPU, not on {device}")
        self._options = dict(bake_options)
        if nthreads:
            self._options.setdefault("threads", int(nthreads))
        self._vertices: list = []
        self._faces: list = []
        self._field: Optional[vlf.Field] = None
        self._geometry: Optional[np.ndarray] = None
        self._primitive: Optional[np.ndarray] = None

    def add_triangles(self, vertex_positions: Any, triangle_indices: Any = None) -> int:
        """Adds a triangle mesh: ``(vertex_positions (V, 3), triangle_indices (F, 3))``, or an
        Open3D ``TriangleMesh`` (tensor or legacy). Returns its geometry id (0, 1, ...)."""
        if triangle_indices is None:
            mesh = vertex_positions
            if hasattr(mesh, "vertex") and hasattr(mesh, "triangle"):
                v, f = _numpy(mesh.vertex["positions"]), _numpy(mesh.triangle["indices"])
            elif hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):
                v, f = np.asarray(mesh.vertices), np.asarray(mesh.triangles)
            else:
                raise TypeError("add_triangles takes (vertex_positions, triangle_indices) or a TriangleMesh")
        else:
            v, f = _numpy(vertex_positions), _numpy(triangle_indices)
        v = np.asarray(v, dtype=np.float32)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertex_positions must have shape (V, 3), not {v.shape}")
        f = np.asarray(f)
        if f.dtype.kind not in "iu":
            raise TypeError(f"triangle_indices must hold integers, not {f.dtype}")
        if f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(f"triangle_indices must have shape (F, 3), not {f.shape}")
        if f.size and (f.min() < 0 or f.max() >= len(v)):
            raise ValueError(f"triangle_indices refer to vertices outside 0..{len(v) - 1}")
        self._vertices.append(v)
        self._faces.append(f.astype(np.int64))
        self._field = None
        return len(self._vertices) - 1

    @property
    def field(self) -> vlf.Field:
        """The field of every geometry added so far (baked, or copied from the cache, on first
        use after an addition)."""
        if self._field is None:
            if not self._vertices:
                raise ValueError("the scene is empty: add_triangles first")
            offsets = np.cumsum([0] + [len(v) for v in self._vertices])[:-1]
            vertices = np.concatenate(self._vertices)
            faces = np.concatenate([f + o for f, o in zip(self._faces, offsets)])
            starts = np.cumsum([0] + [len(f) for f in self._faces])
            field = vlf.bake_arrays(vertices, faces, name="open3d", **vlf._shim_options(self._options, len(faces)))
            source = field.source_indices()
            geometry = np.searchsorted(starts, source, side="right") - 1
            self._geometry = geometry.astype(np.uint32)
            self._primitive = (source - starts[geometry]).astype(np.uint32)
            self._field = field
        return self._field

    def _rays(self, rays: Any):
        r = _numpy(rays)
        if r.dtype not in (np.float32, np.float64):
            r = r.astype(np.float32)
        if r.ndim < 1 or r.shape[-1] != 6:
            raise ValueError(f"rays must have shape (..., 6), not {r.shape}")
        shape = r.shape[:-1]
        flat = r.reshape((-1, 6))
        return flat[:, :3], flat[:, 3:], shape

    def _ids(self, triangle_id: np.ndarray):
        geometry = np.full(triangle_id.shape, INVALID_ID, dtype=np.uint32)
        primitive = np.full(triangle_id.shape, INVALID_ID, dtype=np.uint32)
        hit = triangle_id >= 0
        geometry[hit] = self._geometry[triangle_id[hit]]
        primitive[hit] = self._primitive[triangle_id[hit]]
        return geometry, primitive

    @staticmethod
    def _threads(nthreads: int) -> Optional[int]:
        return int(nthreads) if nthreads else None

    def cast_rays(self, rays: Any, nthreads: int = 0) -> dict:
        """The first hit of each ray ``(..., 6)`` (origin, direction): ``t_hit`` (``inf`` on a
        miss, in units of the direction's length), ``geometry_ids``, ``primitive_ids``
        (``INVALID_ID`` on a miss), ``primitive_uvs`` (..., 2) and ``primitive_normals`` (..., 3)."""
        o, d, shape = self._rays(rays)
        field = self.field
        h = field.closest_hits(o, d, threads=self._threads(nthreads))
        geometry, primitive = self._ids(h.triangle_id)
        return {
            "t_hit": _out(h.t.reshape(shape)),
            "geometry_ids": _out(geometry.reshape(shape)),
            "primitive_ids": _out(primitive.reshape(shape)),
            "primitive_uvs": _out(h.uv.reshape(shape + (2,))),
            "primitive_normals": _out(h.normal.reshape(shape + (3,))),
        }

    def test_occlusions(self, rays: Any, tnear: float = 0.0, tfar: float = np.inf, nthreads: int = 0) -> _Array:
        """Whether each ray ``(..., 6)`` hits anything on ``[tnear, tfar]``: bool ``(...)``."""
        o, d, shape = self._rays(rays)
        hit = self.field.any_hits(o, d, tnear, tfar, threads=self._threads(nthreads))
        return _out(hit.reshape(shape))

    def count_intersections(self, rays: Any, nthreads: int = 0) -> _Array:
        """The number of triangles each ray ``(..., 6)`` hits: int32 ``(...)``."""
        o, d, shape = self._rays(rays)
        counts = self.field.hit_counts(o, d, threads=self._threads(nthreads))
        return _out(counts.astype(np.int32).reshape(shape))

    def list_intersections(self, rays: Any, nthreads: int = 0) -> dict:
        """Every hit of each ray, in order of distance: ``ray_splits`` (N + 1), ``ray_ids``,
        ``t_hit``, ``geometry_ids``, ``primitive_ids`` and ``primitive_uvs`` (H, 2), the rays
        flattened in C order."""
        o, d, _ = self._rays(rays)
        lists = self.field.all_hits(o, d, threads=self._threads(nthreads))
        geometry, primitive = self._ids(lists.triangle_id)
        return {
            "ray_splits": _out(lists.ray_splits.astype(np.uint32)),
            "ray_ids": _out(lists.ray_ids.astype(np.uint32)),
            "t_hit": _out(lists.t),
            "geometry_ids": _out(geometry),
            "primitive_ids": _out(primitive),
            "primitive_uvs": _out(lists.uv),
        }
