"""Type stubs of the native module `vlf._vlf` (crates/vlf-python/src). Use the `vlf` package's
wrappers (`vlf.Field`, `vlf.bake`, `vlf.bake_arrays`): they normalise dtypes, broadcast the
bounds and name the results."""

import pathlib
from typing import Optional, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

class FieldError(ValueError):
    """The bytes are not a valid visibility field, or a packed field is over the size limit."""

class BakeError(RuntimeError):
    """A bake failed: the mesh cannot be imported, or the parameters cannot be met."""

class Field:
    @staticmethod
    def open(path: str, max_unpacked_bytes: Optional[int] = None) -> Field: ...
    @staticmethod
    def from_bytes(data: bytes, max_unpacked_bytes: Optional[int] = None) -> Field: ...
    @property
    def path(self) -> Optional[pathlib.Path]: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def content_hash(self) -> str: ...
    @property
    def input_hash(self) -> str: ...
    @property
    def bounds(self) -> tuple[list[float], list[float]]: ...
    @property
    def bounding_sphere(self) -> tuple[list[float], float]: ...
    @property
    def origin(self) -> list[float]: ...
    @property
    def format_version(self) -> tuple[int, int]: ...
    @property
    def len_bytes(self) -> int: ...
    @property
    def is_packed(self) -> bool: ...
    @property
    def parameters(self) -> dict[str, Optional[float]]: ...
    def provenance(self, prim: int) -> Optional[dict[str, object]]: ...
    def duplicates(self, prim: int) -> list[dict[str, object]]: ...
    def source_indices(self) -> npt.NDArray[np.int64]: ...
    def triangles(self) -> npt.NDArray[np.float64]: ...
    def closest(
        self,
        origins: npt.NDArray[np.floating],
        directions: npt.NDArray[np.floating],
        tmin: npt.NDArray[np.float32],
        tmax: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int64], npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
    def any(
        self,
        origins: npt.NDArray[np.floating],
        directions: npt.NDArray[np.floating],
        tmin: npt.NDArray[np.float32],
        tmax: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.bool_]: ...
    def all(
        self,
        origins: npt.NDArray[np.floating],
        directions: npt.NDArray[np.floating],
        tmin: npt.NDArray[np.float32],
        tmax: npt.NDArray[np.float32],
        max_hits: Optional[int] = None,
        threads: Optional[int] = None,
    ) -> tuple[
        npt.NDArray[np.int64],
        npt.NDArray[np.float32],
        npt.NDArray[np.int64],
        npt.NDArray[np.float32],
        npt.NDArray[np.float32],
    ]: ...
    def count(
        self,
        origins: npt.NDArray[np.floating],
        directions: npt.NDArray[np.floating],
        tmin: npt.NDArray[np.float32],
        tmax: npt.NDArray[np.float32],
        threads: Optional[int] = None,
    ) -> npt.NDArray[np.int64]: ...

def bake_files(
    inputs: Sequence[str],
    output: str,
    directions: Optional[int] = None,
    tiles: Optional[int] = None,
    leaf_size: Optional[int] = None,
    max_depth: Optional[int] = None,
    max_bytes: Optional[int] = None,
    max_bytes_per_triangle: Optional[int] = None,
    cache_dir: Optional[str] = None,
    no_cache: bool = False,
    threads: Optional[int] = None,
) -> tuple[Field, dict[str, object]]: ...
def bake_triangles(
    triangles: npt.NDArray[np.float64],
    name: str,
    output: Optional[str] = None,
    directions: Optional[int] = None,
    tiles: Optional[int] = None,
    leaf_size: Optional[int] = None,
    max_depth: Optional[int] = None,
    max_bytes: Optional[int] = None,
    max_bytes_per_triangle: Optional[int] = None,
    cache_dir: Optional[str] = None,
    no_cache: bool = False,
    threads: Optional[int] = None,
) -> tuple[Field, dict[str, object]]: ...
