//! The `Field` class: a baked field opened from a path or bytes, what it says about itself, and
//! the four queries (closest hit, any hit, all hits, hit counts) on batches of rays. Queries
//! release the GIL and run on the pool the `threads` argument names.

use crate::errors::{open_error, value_error};
use crate::rays::RayArgs;
use crate::threads::Threads;
use numpy::ndarray::{Array2, Array3};
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rayon::prelude::*;
use std::path::PathBuf;
use vlf_runtime::{Hit, OpenOptions, Provenance, hex};

/// An open visibility field (the Python layer's `vlf.Field` wraps it).
#[pyclass(frozen, module = "vlf._vlf")]
pub struct Field {
    field: vlf_runtime::Field,
    path: Option<PathBuf>,
}

/// Hits per task when result columns are filled in parallel.
const CHUNK: usize = 8192;

/// The columns of a list of hits: distance, triangle id (−1 on a miss), barycentrics `(u, v)`
/// and the unit geometric normal (zero on a miss), flattened row by row.
struct Columns {
    t: Vec<f32>,
    prim: Vec<i64>,
    uv: Vec<f32>,
    normal: Vec<f32>,
}

/// The unit normal of triangle `prim` (`(v1 − v0) × (v2 − v0)`, normalised in f64), or zero.
fn normal(field: &vlf_runtime::Field, prim: u32) -> [f32; 3] {
    let Some([a, b, c]) = field.triangle_local(prim) else { return [0.0; 3] };
    let e1: [f64; 3] = std::array::from_fn(|i| b[i] as f64 - a[i] as f64);
    let e2: [f64; 3] = std::array::from_fn(|i| c[i] as f64 - a[i] as f64);
    let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 { n.map(|c| (c / len) as f32) } else { [0.0; 3] }
}

/// Fills the columns of `hits` (slices of the same rows).
fn fill(field: &vlf_runtime::Field, hits: &[Hit], t: &mut [f32], prim: &mut [i64], uv: &mut [f32], nrm: &mut [f32]) {
    for (i, h) in hits.iter().enumerate() {
        t[i] = h.t;
        let hit = h.prim != Hit::MISS.prim;
        prim[i] = if hit { h.prim as i64 } else { -1 };
        uv[2 * i] = h.u;
        uv[2 * i + 1] = h.v;
        let nv = if hit { normal(field, h.prim) } else { [0.0; 3] };
        nrm[3 * i..3 * i + 3].copy_from_slice(&nv);
    }
}

impl Columns {
    fn new(field: &vlf_runtime::Field, hits: &[Hit], parallel: bool) -> Columns {
        let n = hits.len();
        let mut c = Columns { t: vec![0.0; n], prim: vec![0; n], uv: vec![0.0; 2 * n], normal: vec![0.0; 3 * n] };
        if parallel {
            hits.par_chunks(CHUNK)
                .zip(c.t.par_chunks_mut(CHUNK))
                .zip(c.prim.par_chunks_mut(CHUNK))
                .zip(c.uv.par_chunks_mut(2 * CHUNK).zip(c.normal.par_chunks_mut(3 * CHUNK)))
                .for_each(|(((hits, t), prim), (uv, nrm))| fill(field, hits, t, prim, uv, nrm));
        } else {
            fill(field, hits, &mut c.t, &mut c.prim, &mut c.uv, &mut c.normal);
        }
        c
    }

    /// `(t, triangle_id, uv, normal)` as numpy arrays, without copies.
    fn into_py<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let n = self.t.len();
        let shape_err = |e: numpy::ndarray::ShapeError| value_error(e.to_string());
        let uv = PyArray2::from_owned_array(py, Array2::from_shape_vec((n, 2), self.uv).map_err(shape_err)?);
        let normal = PyArray2::from_owned_array(py, Array2::from_shape_vec((n, 3), self.normal).map_err(shape_err)?);
        PyTuple::new(
            py,
            [
                PyArray1::from_vec(py, self.t).into_any(),
                PyArray1::from_vec(py, self.prim).into_any(),
                uv.into_any(),
                normal.into_any(),
            ],
        )
    }
}

fn provenance_dict<'py>(py: Python<'py>, p: &Provenance<'_>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("input", p.input)?;
    d.set_item("name", p.name)?;
    let kind = match p.kind {
        1 => "obj",
        2 => "gltf",
        3 => "program",
        _ => "unknown",
    };
    d.set_item("kind", kind)?;
    d.set_item("mesh", p.mesh)?;
    d.set_item("primitive", p.primitive)?;
    d.set_item("node", p.node)?;
    d.set_item("material", p.material)?;
    d.set_item("index", p.index)?;
    Ok(d)
}

/// The most bytes a query holds per ray: the ray (32), its hit (16) and the columns made of it
/// (32).
const BYTES_PER_RAY: usize = 80;

/// The bytes an all-hits query plans per hit while it makes its results: at most 48 are held at
/// once (a hit in its thread's list, which grows by doubling, so up to three copies' room while
/// it moves; then in the stitched list and in the columns made of it, 16 + 32), and a quarter
/// more is left for everything else.
const BYTES_PER_HIT: u64 = 64;

/// A `MemoryError` if the arrays of a query on `n` rays cannot be allocated: checked before the
/// work, so that a huge (say, broadcast) batch is refused instead of aborting the interpreter
/// when an allocation fails midway.
fn reserve_for(n: usize) -> PyResult<()> {
    let too_much = || {
        PyMemoryError::new_err(format!(
            "{n} rays: a query holds about {BYTES_PER_RAY} bytes per ray ({:.3e} bytes in all), more than \
             can be allocated; trace them in smaller batches",
            n as f64 * BYTES_PER_RAY as f64
        ))
    };
    let bytes = n.checked_mul(BYTES_PER_RAY).ok_or_else(too_much)?;
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(bytes).map_err(|_| too_much())
}

impl Field {
    pub fn new(field: vlf_runtime::Field, path: Option<PathBuf>) -> Field {
        Field { field, path }
    }

    /// Runs `query` on the checked rays with the GIL released, in the pool of `threads`.
    fn run<R: Send>(
        &self,
        py: Python<'_>,
        args: &RayArgs<'_>,
        threads: Option<usize>,
        query: impl FnOnce(&vlf_runtime::Field, &[vlf_runtime::Ray], bool) -> R + Send,
    ) -> PyResult<R> {
        reserve_for(args.len())?;
        let pool = Threads::new(threads)?;
        let views = args.views();
        let field = &self.field;
        py.detach(|| {
            pool.run(|| {
                let rays = views.rays(pool.parallel())?;
                Ok::<R, String>(query(field, &rays, pool.parallel()))
            })
        })
        .map_err(value_error)
    }
}

#[pymethods]
impl Field {
    /// Opens the field file at `path` (memory-mapped; a packed field is decoded into memory).
    #[staticmethod]
    #[pyo3(signature = (path, max_unpacked_bytes=None))]
    fn open(py: Python<'_>, path: PathBuf, max_unpacked_bytes: Option<u64>) -> PyResult<Field> {
        let mut options = OpenOptions::new();
        if let Some(max) = max_unpacked_bytes {
            options.max_unpacked_bytes(max);
        }
        let field = py.detach(|| options.open(&path)).map_err(open_error)?;
        Ok(Field::new(field, Some(path)))
    }

    /// Opens a field from its bytes (copied once into an aligned buffer the field owns).
    #[staticmethod]
    #[pyo3(signature = (data, max_unpacked_bytes=None))]
    fn from_bytes(py: Python<'_>, data: &[u8], max_unpacked_bytes: Option<u64>) -> PyResult<Field> {
        let mut options = OpenOptions::new();
        if let Some(max) = max_unpacked_bytes {
            options.max_unpacked_bytes(max);
        }
        let field = py.detach(|| options.from_bytes(data)).map_err(open_error)?;
        Ok(Field::new(field, None))
    }

    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }

    #[getter]
    fn triangle_count(&self) -> u32 {
        self.field.triangle_count()
    }

    #[getter]
    fn content_hash(&self) -> String {
        hex(&self.field.content_hash())
    }

    #[getter]
    fn input_hash(&self) -> String {
        hex(&self.field.input_hash())
    }

    #[getter]
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.field.bounds()
    }

    #[getter]
    fn bounding_sphere(&self) -> ([f64; 3], f64) {
        self.field.bounding_sphere()
    }

    #[getter]
    fn origin(&self) -> [f64; 3] {
        self.field.origin()
    }

    #[getter]
    fn format_version(&self) -> (u16, u16) {
        self.field.format_version()
    }

    #[getter]
    fn len_bytes(&self) -> u64 {
        self.field.len_bytes()
    }

    #[getter]
    fn is_packed(&self) -> bool {
        self.field.is_packed()
    }

    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = self.field.parameters();
        let d = PyDict::new(py);
        d.set_item("directions", p.directions)?;
        d.set_item("lattice_n", p.lattice_n)?;
        d.set_item("tiles", p.tiles)?;
        d.set_item("leaf_size", p.leaf_size)?;
        d.set_item("max_depth", p.max_depth)?;
        d.set_item("margin", p.margin)?;
        d.set_item("requested_directions", p.requested_directions)?;
        d.set_item("requested_tiles", p.requested_tiles)?;
        d.set_item("max_bytes", p.max_bytes)?;
        d.set_item("max_bytes_per_triangle", p.max_bytes_per_triangle)?;
        Ok(d)
    }

    /// Where triangle `prim` came from, as a dict; `None` if the id is out of range.
    fn provenance<'py>(&self, py: Python<'py>, prim: i64) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Ok(id) = u32::try_from(prim) else { return Ok(None) };
        self.field.provenance(id).map(|p| provenance_dict(py, &p)).transpose()
    }

    /// The input triangles merged into triangle `prim` (same three vertices), as dicts.
    fn duplicates<'py>(&self, py: Python<'py>, prim: i64) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let Ok(id) = u32::try_from(prim) else { return Ok(Vec::new()) };
        self.field.duplicates(id).map(|p| provenance_dict(py, &p)).collect()
    }

    /// For every triangle, its index within its source (the face index of an array bake), or
    /// −1 if its provenance is unreadable: int64 `(F,)`.
    fn source_indices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let n = self.field.triangle_count();
        let v: Vec<i64> = (0..n).map(|i| self.field.provenance(i).map_or(-1, |p| p.index as i64)).collect();
        PyArray1::from_vec(py, v)
    }

    /// Every triangle's vertices in world coordinates: float64 `(F, 3, 3)`.
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let n = self.field.triangle_count();
        let flat: Vec<f64> =
            (0..n).flat_map(|i| self.field.triangle(i).unwrap_or_default().into_iter().flatten()).collect();
        let a = Array3::from_shape_vec((n as usize, 3, 3), flat).map_err(|e| value_error(e.to_string()))?;
        Ok(PyArray3::from_owned_array(py, a))
    }

    /// Closest hits: `(t, triangle_id, uv, normal)`.
    #[pyo3(signature = (origins, directions, tmin, tmax, threads=None))]
    fn closest<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let args = RayArgs::extract(origins, directions, tmin, tmax)?;
        let columns = self.run(py, &args, threads, |field, rays, parallel| {
            let mut hits = vec![Hit::MISS; rays.len()];
            if parallel {
                field.par_closest_hits(rays, &mut hits);
            } else {
                field.closest_hits(rays, &mut hits);
            }
            Columns::new(field, &hits, parallel)
        })?;
        columns.into_py(py)
    }

    /// Any hit: bool `(N,)`.
    #[pyo3(signature = (origins, directions, tmin, tmax, threads=None))]
    fn any<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let args = RayArgs::extract(origins, directions, tmin, tmax)?;
        let hit = self.run(py, &args, threads, |field, rays, parallel| {
            let mut out = vec![false; rays.len()];
            if parallel {
                field.par_any_hits(rays, &mut out);
            } else {
                field.any_hits(rays, &mut out);
            }
            out
        })?;
        Ok(PyArray1::from_vec(py, hit))
    }

    /// Every hit, at most `max_hits` per ray (`None`: all): `(ray_splits, t, triangle_id, uv,
    /// normal)`, ray `i`'s hits at `ray_splits[i]:ray_splits[i + 1]`, in order of `t`.
    #[pyo3(signature = (origins, directions, tmin, tmax, max_hits=None, threads=None))]
    #[allow(clippy::too_many_arguments)]
    fn all<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
        max_hits: Option<usize>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let args = RayArgs::extract(origins, directions, tmin, tmax)?;
        let max = max_hits.unwrap_or(usize::MAX);
        // Every ray may hit every triangle: the batch stops once its hits would not fit in memory.
        let (budget, why) = vlf_bake::memory::budget();
        let limit = usize::try_from(budget / BYTES_PER_HIT).unwrap_or(usize::MAX);
        let found = self.run(py, &args, threads, |field, rays, parallel| {
            let view = field.view();
            let lists = if parallel {
                view.par_all_hits_batch_within(rays, max, limit)
            } else {
                view.all_hits_batch_within(rays, max, limit)
            }?;
            let splits: Vec<i64> = lists.offsets.iter().map(|&o| o as i64).collect();
            Ok((splits, Columns::new(field, &lists.hits, parallel)))
        })?;
        let (splits, columns) = found.map_err(|e: vlf_runtime::TooManyHits| {
            PyMemoryError::new_err(format!(
                "all_hits on {} rays: {e}, and their results take about {BYTES_PER_HIT} bytes a hit: more than the \
                 {} that may be used ({why}); pass max_hits, or trace fewer rays at a time",
                args.len(),
                vlf_bake::params::human_bytes(budget)
            ))
        })?;
        let mut items = vec![PyArray1::from_vec(py, splits).into_any()];
        items.extend(columns.into_py(py)?.iter());
        PyTuple::new(py, items)
    }

    /// Hit counts (each triangle once): int64 `(N,)`.
    #[pyo3(signature = (origins, directions, tmin, tmax, threads=None))]
    fn count<'py>(
        &self,
        py: Python<'py>,
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let args = RayArgs::extract(origins, directions, tmin, tmax)?;
        let counts = self.run(py, &args, threads, |field, rays, parallel| {
            let mut out = vec![0u32; rays.len()];
            if parallel {
                field.view().par_hit_counts(rays, &mut out);
            } else {
                field.view().hit_counts(rays, &mut out);
            }
            out.into_iter().map(i64::from).collect::<Vec<i64>>()
        })?;
        Ok(PyArray1::from_vec(py, counts))
    }

    fn __repr__(&self) -> String {
        let p = self.field.parameters();
        let at = self.path.as_ref().map_or_else(|| "from bytes".to_owned(), |p| p.display().to_string());
        format!(
            "<vlf.Field {at}: {} triangles, {} directions × {}² tiles, content hash {}>",
            self.field.triangle_count(),
            p.directions,
            p.tiles,
            &hex(&self.field.content_hash())[..16]
        )
    }
}
