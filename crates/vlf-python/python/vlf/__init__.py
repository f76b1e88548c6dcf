"""Baked visibility fields for ray casting, with numpy in and out.

A field is baked once from a mesh (files or arrays), saved, and opened instantly (memory-mapped)
by any later run. It answers, for batches of rays given as numpy arrays:

- :meth:`Field.closest_hits`: distance, triangle id (-1 on a miss), barycentrics, normal;
- :meth:`Field.any_hits`: whether anything is hit (shadow rays);
- :meth:`Field.all_hits`: every hit along each ray, in order of distance, each triangle once;
- :meth:`Field.hit_counts`: how many triangles each ray crosses.

Queries release the GIL and run on every core (or on ``threads`` threads). The hits are those of
a watertight triangle test: a ray through a shared edge hits one of its triangles (or both),
never neither.

Drop-in shims: :class:`vlf.trimesh.RayMeshIntersector` and :class:`vlf.open3d.RaycastingScene`.

>>> import numpy as np, vlf
>>> vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
>>> field = vlf.bake_arrays(vertices, [[0, 1, 2]], directions=9, tiles=4, no_cache=True)
>>> hits = field.closest_hits([[0.2, 0.2, 1.0]], [[0.0, 0.0, -1.0]])
>>> float(hits.t[0]), int(hits.triangle_id[0])
(1.0, 0)
"""

from __future__ import annotations

import os
from typing import Any, NamedTuple, Optional, Sequence, Union

import numpy as np

from . import _vlf
from ._vlf import BakeError, FieldError, __version__

__all__ = [
    "BakeError",
    "Field",
    "FieldError",
    "HitLists",
    "Hits",
    "bake",
    "bake_arrays",
    "default_cache_dir",
    "open",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


class Hits(NamedTuple):
    """The closest hit of each of N rays."""

    t: np.ndarray
    """(N,) float32: the ray parameter of the hit (the point is ``origin + t * direction``);
    ``inf`` on a miss."""
    triangle_id: np.ndarray
    """(N,) int64: the field's triangle id, ``-1`` on a miss."""
    uv: np.ndarray
    """(N, 2) float32: barycentric weights ``(u, v)`` of the triangle's second and third vertex
    (the point is ``(1 - u - v) * v0 + u * v1 + v * v2``); zero on a miss."""
    normal: np.ndarray
    """(N, 3) float32: the unit geometric normal ``(v1 - v0) x (v2 - v0)`` normalised; zero on a
    miss."""

    @property
    def hit(self) -> np.ndarray:
        """(N,) bool: whether each ray hit something."""
        return self.triangle_id >= 0

    @property
    def barycentric(self) -> np.ndarray:
        """(N, 3) float32: the weights ``(1 - u - v, u, v)`` of the three vertices."""
        return _barycentric(self.uv)


class HitLists(NamedTuple):
    """Every hit of each of N rays, ray after ray, each ray's hits in order of ``t``: ray ``i``'s
    hits are rows ``ray_splits[i]:ray_splits[i + 1]`` of the other arrays (Open3D's layout)."""

    ray_splits: np.ndarray
    """(N + 1,) int64: offsets of each ray's hits, from 0 to H."""
    ray_ids: np.ndarray
    """(H,) int64: the ray of each hit."""
    t: np.ndarray
    """(H,) float32: the ray parameter of each hit."""
    triangle_id: np.ndarray
    """(H,) int64: the triangle of each hit."""
    uv: np.ndarray
    """(H, 2) float32: barycentric weights of the second and third vertex."""
    normal: np.ndarray
    """(H, 3) float32: unit geometric normals."""

    @property
    def counts(self) -> np.ndarray:
        """(N,) int64: the number of hits of each ray (as returned, so at most ``max_hits``)."""
        return np.diff(self.ray_splits)

    @property
    def barycentric(self) -> np.ndarray:
        """(H, 3) float32: the weights ``(1 - u - v, u, v)``."""
        return _barycentric(self.uv)

    def ray(self, i: int) -> Hits:
        """The hits of ray ``i``, in order of ``t``."""
        s = slice(int(self.ray_splits[i]), int(self.ray_splits[i + 1]))
        return Hits(self.t[s], self.triangle_id[s], self.uv[s], self.normal[s])


def _barycentric(uv: np.ndarray) -> np.ndarray:
    w = (1.0 - uv[:, 0] - uv[:, 1]).astype(np.float32)
    return np.column_stack((w, uv[:, 0], uv[:, 1]))


def _vectors(a: Any, name: str) -> np.ndarray:
    """``a`` as an array the native module reads in place: float32 or float64 in native byte
    order (other dtypes converted to float64), any strides, shape (N, 3) or (3,)."""
    a = np.asarray(a)
    if a.dtype not in (np.float32, np.float64):
        if a.dtype.kind not in "fiub":
            raise TypeError(f"`{name}` must hold numbers, not {a.dtype}")
        a = a.astype(np.float64)
    elif not a.dtype.isnative:
        a = a.astype(a.dtype.newbyteorder("="))
    a = _aligned(a)
    if a.ndim == 1 and a.shape[0] == 3:
        return a
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"`{name}` must have shape (N, 3), not {a.shape}")
    return a


def _rays(origins: Any, directions: Any, tmin: Any, tmax: Any):
    o = _vectors(origins, "origins")
    d = _vectors(directions, "directions")
    # A single origin (or direction) for every ray: broadcast without a copy.
    if o.ndim == 1 and d.ndim == 1:
        o, d = o[None, :], d[None, :]
    elif o.ndim == 1:
        o = np.broadcast_to(o, (d.shape[0], 3))
    elif d.ndim == 1:
        d = np.broadcast_to(d, (o.shape[0], 3))
    if o.shape[0] != d.shape[0]:
        raise ValueError(
            f"`origins` has {o.shape[0]} rows and `directions` {d.shape[0]}: one origin per direction"
        )
    n = o.shape[0]
    return o, d, _bound(tmin, n, "tmin"), _bound(tmax, n, "tmax")


def _aligned(a: np.ndarray) -> np.ndarray:
    """``a``, or an aligned copy of it: a view into packed records (a field of a structured array)
    is not aligned to its values, and the native module reads arrays in place."""
    return a if a.flags.aligned else np.array(a, order="C", copy=True)


def _bound(value: Any, n: int, name: str) -> np.ndarray:
    a = _aligned(np.asarray(value, dtype=np.float32))
    if a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
        raise ValueError(f"`{name}` must be a number or have shape ({n},), not {a.shape}")
    return np.broadcast_to(a, (n,))


def _threads(threads: Optional[int]) -> Optional[int]:
    if threads is None:
        return None
    threads = int(threads)
    if threads < 0:
        raise ValueError(f"threads = {threads}: give a count of threads, or 0 or None for every core")
    return threads


class Field:
    """A baked visibility field, opened. Immutable and safe to share between threads.

    Open one with :func:`vlf.open` (or :meth:`Field.open`, :meth:`Field.from_bytes`), or bake one
    with :func:`vlf.bake` or :func:`vlf.bake_arrays`.
    """

    __slots__ = ("_inner", "bake_info")

    def __init__(self, inner: "_vlf.Field", bake_info: Optional[dict] = None):
        self._inner = inner
        #: What the bake that made this field did (``None`` for a field that was opened): the
        #: cache status (``"hit"``, ``"miss"``, ``"disabled"``), seconds, triangles, warnings.
        self.bake_info = bake_info

    # -- opening -------------------------------------------------------------------------

    @classmethod
    def open(cls, path: PathLike, *, max_unpacked_bytes: Optional[int] = None) -> "Field":
        """Opens the field file at ``path`` by memory-mapping it: the header, the section table
        and the content hash are checked, nothing else is read. A packed field is decoded into
        memory, refused over ``max_unpacked_bytes`` (by default, three quarters of the memory the
        system reports available, or what ``ulimit -v`` leaves). Raises ``FileNotFoundError`` (or another
        ``OSError``) if the file cannot be read and :class:`FieldError` if it is not a valid
        field."""
        return cls(_vlf.Field.open(os.fsdecode(path), max_unpacked_bytes))

    @classmethod
    def from_bytes(cls, data: Union[bytes, bytearray, memoryview], *, max_unpacked_bytes: Optional[int] = None) -> "Field":
        """Opens a field from its bytes (copied once). Raises :class:`FieldError` if they are not
        a valid field."""
        return cls(_vlf.Field.from_bytes(bytes(data), max_unpacked_bytes))

    # -- what the field says about itself ---------------------------------------------------

    @property
    def path(self) -> Optional[str]:
        """The file the field was opened from, or ``None``."""
        p = self._inner.path
        return None if p is None else os.fspath(p)

    @property
    def triangle_count(self) -> int:
        """The number of triangles; ids run from 0 to ``triangle_count - 1``."""
        return self._inner.triangle_count

    @property
    def content_hash(self) -> str:
        """BLAKE3 of the field's contents, 64 hex digits: the same for the same bake."""
        return self._inner.content_hash

    @property
    def input_hash(self) -> str:
        """BLAKE3 of what the bake was asked (triangles, provenance, request), 64 hex digits."""
        return self._inner.input_hash

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64: the lower and upper corner of the box around every vertex."""
        lo, hi = self._inner.bounds
        return np.array([lo, hi], dtype=np.float64)

    @property
    def bounding_sphere(self) -> tuple:
        """``(center (3,) float64, radius)``: every triangle lies inside this sphere."""
        c, r = self._inner.bounding_sphere
        return np.array(c, dtype=np.float64), float(r)

    @property
    def format_version(self) -> tuple:
        """The file format version, ``(major, minor)``."""
        return tuple(self._inner.format_version)

    @property
    def size_bytes(self) -> int:
        """The size of the field in bytes (for a packed field, decoded)."""
        return self._inner.len_bytes

    @property
    def is_packed(self) -> bool:
        """Whether the file is packed (zstd sections, decoded at open)."""
        return self._inner.is_packed

    @property
    def parameters(self) -> dict:
        """The bake's parameters: ``directions``, ``tiles``, ``leaf_size``, ``max_depth``,
        ``margin``, ``lattice_n``, what was asked for (``requested_directions``,
        ``requested_tiles``: ``None`` if chosen automatically), ``max_bytes`` and
        ``max_bytes_per_triangle``."""
        return dict(self._inner.parameters)

    def provenance(self, triangle_id: int) -> Optional[dict]:
        """Where triangle ``triangle_id`` came from: ``input`` (file name), ``name`` (object or
        mesh), ``kind`` (``"obj"``, ``"gltf"``, ``"program"``), ``mesh``, ``primitive``,
        ``node``, ``material`` and ``index`` (the face's index in its source: for a bake from
        arrays, the row of ``faces``). ``None`` for an id out of range."""
        return self._inner.provenance(int(triangle_id))

    def duplicates(self, triangle_id: int) -> list:
        """Input faces merged into triangle ``triangle_id`` because they have exactly its
        vertices (a ray cannot tell them apart), as :meth:`provenance` dicts."""
        return self._inner.duplicates(int(triangle_id))

    def source_indices(self) -> np.ndarray:
        """(F,) int64: each triangle's index in its source (see :meth:`provenance`); -1 where
        unreadable. For a field baked from arrays, ``faces[source_indices()]`` are the faces in
        the field's order."""
        return self._inner.source_indices()

    def triangles(self) -> np.ndarray:
        """(F, 3, 3) float64: every triangle's vertices in world coordinates, as stored (f32
        relative to the scene's centre)."""
        return self._inner.triangles()

    # -- queries ------------------------------------------------------------------------

    def closest_hits(self, origins, directions, tmin=0.0, tmax=np.inf, *, threads: Optional[int] = None) -> Hits:
        """The closest hit of each ray on ``[tmin, tmax]``.

        ``origins`` and ``directions``: (N, 3) arrays (float32 or float64 are read in place with
        any strides; other dtypes are converted), or one (3,) row for every ray. Directions need
        not be unit length: ``t`` is in units of the direction's length. ``tmin``, ``tmax``: a
        number or (N,) per ray. ``threads``: ``None`` or 0 for every core, 1 for the calling
        thread, k for k threads. A non-finite origin or direction, a zero direction, a NaN bound
        or ``tmin > tmax`` raises ``ValueError`` naming the ray.
        """
        o, d, lo, hi = _rays(origins, directions, tmin, tmax)
        return Hits(*self._inner.closest(o, d, lo, hi, _threads(threads)))

    def any_hits(self, origins, directions, tmin=0.0, tmax=np.inf, *, threads: Optional[int] = None) -> np.ndarray:
        """(N,) bool: whether each ray hits anything on ``[tmin, tmax]``; the first hit found
        ends a ray's search. Arguments as :meth:`closest_hits`."""
        o, d, lo, hi = _rays(origins, directions, tmin, tmax)
        return self._inner.any(o, d, lo, hi, _threads(threads))

    def all_hits(
        self, origins, directions, tmin=0.0, tmax=np.inf, *, max_hits: Optional[int] = None, threads: Optional[int] = None
    ) -> HitLists:
        """Every hit of each ray on ``[tmin, tmax]``, in order of ``t`` (then triangle id), each
        triangle once even where it lies in several of the field's cells, at most ``max_hits``
        per ray (the closest ones; ``None`` for all). The search of a ray stops once its
        ``max_hits`` closest hits are known. Arguments as :meth:`closest_hits`. Raises
        ``MemoryError`` if the batch's hits would not fit in memory (about 64 bytes a hit, against
        three quarters of the memory available): pass ``max_hits`` or trace fewer rays at once."""
        o, d, lo, hi = _rays(origins, directions, tmin, tmax)
        if max_hits is not None:
            max_hits = int(max_hits)
            if max_hits < 0:
                raise ValueError(f"max_hits = {max_hits}: give a number of hits, or None for all")
        splits, t, prim, uv, normal = self._inner.all(o, d, lo, hi, max_hits, _threads(threads))
        ray_ids = np.repeat(np.arange(len(splits) - 1, dtype=np.int64), np.diff(splits))
        return HitLists(splits, ray_ids, t, prim, uv, normal)

    def hit_counts(self, origins, directions, tmin=0.0, tmax=np.inf, *, threads: Optional[int] = None) -> np.ndarray:
        """(N,) int64: how many triangles each ray hits on ``[tmin, tmax]``, each counted once.
        From a point inside a closed mesh the count is odd. Arguments as :meth:`closest_hits`."""
        o, d, lo, hi = _rays(origins, directions, tmin, tmax)
        return self._inner.count(o, d, lo, hi, _threads(threads))

    def __repr__(self) -> str:
        return repr(self._inner)


def open(source: Union[PathLike, bytes, bytearray, memoryview], *, max_unpacked_bytes: Optional[int] = None) -> Field:
    """Opens a field from a path (memory-mapped) or from bytes. See :meth:`Field.open`."""
    if isinstance(source, (bytes, bytearray, memoryview)):
        return Field.from_bytes(source, max_unpacked_bytes=max_unpacked_bytes)
    return Field.open(source, max_unpacked_bytes=max_unpacked_bytes)


def default_cache_dir() -> str:
    """The cache directory the shims use when given none: ``$VLF_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/vlf``, else ``~/.cache/vlf``."""
    env = os.environ.get("VLF_CACHE_DIR")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "vlf")


_BAKE_OPTIONS = (
    "directions",
    "tiles",
    "leaf_size",
    "max_depth",
    "max_bytes",
    "max_bytes_per_triangle",
    "cache_dir",
    "no_cache",
    "threads",
)


def _options(options: dict) -> dict:
    unknown = sorted(set(options) - set(_BAKE_OPTIONS))
    if unknown:
        raise TypeError(f"unknown bake option(s) {', '.join(unknown)}; the options are {', '.join(_BAKE_OPTIONS)}")
    out = dict(options)
    if out.get("cache_dir") is not None:
        out["cache_dir"] = os.fsdecode(out["cache_dir"])
    if out.get("threads") is not None:
        out["threads"] = _threads(out["threads"])
    out["no_cache"] = bool(out.get("no_cache", False))
    return out


def _shim_options(options: dict, triangles: int) -> dict:
    """The shims' bake options: the library's defaults (which give any mesh, however small, a
    budget of at least 16 MiB, and 2.5 KiB for each of its first 100,000 triangles, less and less
    past them down to 1 KiB at 625,000), through the
    cache unless told otherwise. ``triangles`` is unused and kept for the shims' calls."""
    del triangles
    out = dict(options)
    out.setdefault("cache_dir", default_cache_dir())
    return out


def bake(inputs: Union[PathLike, Sequence[PathLike]], output: PathLike, **options) -> Field:
    """Bakes mesh files (``.obj``, ``.gltf``, ``.glb``; several make one scene) into the field
    file ``output``, as ``vlf-bake bake`` does, and opens it.

    Options (those of the command line): ``directions``, ``tiles`` (``None``: chosen within the
    budgets), ``leaf_size``, ``max_depth``, ``max_bytes``, ``max_bytes_per_triangle``,
    ``cache_dir`` (else ``$VLF_CACHE_DIR``; a bake of unchanged inputs is then a copy),
    ``no_cache``, ``threads``. The returned field's ``bake_info`` says what happened. Raises
    ``FileNotFoundError`` for a missing input, :class:`BakeError` for a mesh that cannot be
    imported or baked, ``ValueError`` for bad options.
    """
    if isinstance(inputs, (str, bytes, os.PathLike)):
        inputs = [inputs]
    paths = [os.fsdecode(p) for p in inputs]
    inner, info = _vlf.bake_files(paths, os.fsdecode(output), **_options(options))
    return Field(inner, info)


def _triangles(vertices: Any, faces: Any) -> np.ndarray:
    v = np.asarray(vertices)
    if v.dtype.kind not in "fiu":
        raise TypeError(f"`vertices` must hold numbers, not {v.dtype}")
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"`vertices` must have shape (V, 3), not {v.shape}")
    f = np.asarray(faces)
    if f.dtype.kind == "f":
        if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
            raise ValueError("`faces` must hold whole vertex indices")
        f = f.astype(np.int64)
    elif f.dtype.kind not in "iu":
        raise TypeError(f"`faces` must hold integer vertex indices, not {f.dtype}")
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"`faces` must have shape (F, 3), not {f.shape}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        bad = int(f.min()) if f.min() < 0 else int(f.max())
        raise ValueError(f"`faces` holds the vertex index {bad}, out of range for {len(v)} vertices")
    if len(f) == 0:
        raise ValueError("no faces to bake")
    return np.ascontiguousarray(v[f], dtype=np.float64)


def bake_arrays(vertices: Any, faces: Any, output: Optional[PathLike] = None, *, name: str = "arrays", **options) -> Field:
    """Bakes a triangle mesh given as arrays: ``vertices`` (V, 3) of any float or integer dtype
    and ``faces`` (F, 3) of vertex indices (a trimesh mesh's ``vertices`` and ``faces``). With
    ``output``, the field is written there and mapped; without, it is baked in a temporary
    directory and held in memory. Triangle ``i`` of the field keeps the row of ``faces`` it came
    from as its provenance index (:meth:`Field.source_indices`): the baker drops zero-area faces
    and merges faces with identical vertices, and may store them in another order. ``name``
    names the source in the provenance. Options as :func:`bake`.
    """
    tris = _triangles(vertices, faces)
    out = None if output is None else os.fsdecode(output)
    inner, info = _vlf.bake_triangles(tris, str(name), out, **_options(options))
    return Field(inner, info)
