//! Rays from numpy arrays: origins and directions `(N, 3)` in float32 or float64 with any strides
//! (read in place: no copy of the caller's arrays), `tmin` and `tmax` `(N,)` float32 (the Python
//! layer broadcasts scalars with zero strides). Every ray is checked; the first bad one is named
//! in a `ValueError`.

use crate::errors::value_error;
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{PyArray, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use rayon::prelude::*;
use vlf_runtime::Ray;

/// An `(N, 3)` array borrowed from Python, read-only.
pub enum Held<'py> {
    F32(PyReadonlyArray2<'py, f32>),
    F64(PyReadonlyArray2<'py, f64>),
}

/// A view of a [`Held`] array, to read without the GIL.
#[derive(Clone, Copy)]
pub enum Vectors<'a> {
    F32(ArrayView2<'a, f32>),
    F64(ArrayView2<'a, f64>),
}

impl<'py> Held<'py> {
    /// `obj` as an `(N, 3)` float32 or float64 array, or a `TypeError` or `ValueError` naming
    /// the argument.
    pub fn extract(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Held<'py>> {
        let held = if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, f32>>() {
            Held::F32(a)
        } else if let Ok(a) = obj.extract::<PyReadonlyArray2<'py, f64>>() {
            Held::F64(a)
        } else {
            return Err(PyTypeError::new_err(format!(
                "`{name}` must be a numpy array of float32 or float64 with shape (N, 3)"
            )));
        };
        let shape = held.shape();
        if shape[1] != 3 {
            return Err(value_error(format!("`{name}` must have shape (N, 3), not ({}, {})", shape[0], shape[1])));
        }
        match &held {
            Held::F32(a) => aligned(a, name)?,
            Held::F64(a) => aligned(a, name)?,
        }
        Ok(held)
    }

    fn shape(&self) -> [usize; 2] {
        let s = match self {
            Held::F32(a) => a.shape(),
            Held::F64(a) => a.shape(),
        };
        [s[0], s[1]]
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.shape()[0]
    }

    pub fn view(&self) -> Vectors<'_> {
        match self {
            Held::F32(a) => Vectors::F32(a.as_array()),
            Held::F64(a) => Vectors::F64(a.as_array()),
        }
    }
}

impl Vectors<'_> {
    /// Row `i`, rounded to f32 (the precision of a ray).
    #[inline]
    fn row(&self, i: usize) -> [f32; 3] {
        match self {
            Vectors::F32(a) => [a[[i, 0]], a[[i, 1]], a[[i, 2]]],
            Vectors::F64(a) => [a[[i, 0]] as f32, a[[i, 1]] as f32, a[[i, 2]] as f32],
        }
    }
}

/// A `ValueError` unless `a`'s data and strides are aligned to its element type: numpy's views
/// into packed records are not, and reading them in place would read the wrong bytes (the
/// Python layer copies such arrays before they get here).
fn aligned<T: numpy::Element, D: numpy::ndarray::Dimension>(a: &Bound<'_, PyArray<T, D>>, name: &str) -> PyResult<()> {
    let size = std::mem::size_of::<T>() as isize;
    let strides_ok = a.strides().iter().zip(a.shape()).all(|(&s, &n)| n <= 1 || s % size == 0);
    let data_ok = a.len() == 0 || (a.data() as usize).is_multiple_of(std::mem::align_of::<T>());
    if strides_ok && data_ok {
        Ok(())
    } else {
        Err(value_error(format!(
            "`{name}` is not aligned in memory (strides {:?} bytes for {size}-byte values): copy it first, \
             e.g. with numpy.ascontiguousarray",
            a.strides()
        )))
    }
}

/// The arguments of a query, borrowed from Python.
pub struct RayArgs<'py> {
    origins: Held<'py>,
    directions: Held<'py>,
    tmin: PyReadonlyArray1<'py, f32>,
    tmax: PyReadonlyArray1<'py, f32>,
}

/// What the queries read: views of [`RayArgs`], `Send`, for use with the GIL released.
#[derive(Clone, Copy)]
pub struct RayViews<'a> {
    origins: Vectors<'a>,
    directions: Vectors<'a>,
    tmin: ArrayView1<'a, f32>,
    tmax: ArrayView1<'a, f32>,
    len: usize,
}

impl<'py> RayArgs<'py> {
    /// Checks shapes: `origins` and `directions` `(N, 3)`, `tmin` and `tmax` `(N,)`.
    pub fn extract(
        origins: &Bound<'py, PyAny>,
        directions: &Bound<'py, PyAny>,
        tmin: &Bound<'py, PyAny>,
        tmax: &Bound<'py, PyAny>,
    ) -> PyResult<RayArgs<'py>> {
        let origins = Held::extract(origins, "origins")?;
        let directions = Held::extract(directions, "directions")?;
        if origins.len() != directions.len() {
            return Err(value_error(format!(
                "`origins` has {} rows and `directions` {}: one origin per direction",
                origins.len(),
                directions.len()
            )));
        }
        let bound = |obj: &Bound<'py, PyAny>, name: &str| -> PyResult<PyReadonlyArray1<'py, f32>> {
            let a = obj
                .extract::<PyReadonlyArray1<'py, f32>>()
                .map_err(|_| PyTypeError::new_err(format!("`{name}` must be a float32 numpy array of shape (N,)")))?;
            if a.len() != origins.len() {
                return Err(value_error(format!("`{name}` has {} values for {} rays", a.len(), origins.len())));
            }
            aligned(&a, name)?;
            Ok(a)
        };
        let (tmin, tmax) = (bound(tmin, "tmin")?, bound(tmax, "tmax")?);
        Ok(RayArgs { origins, directions, tmin, tmax })
    }

    pub fn len(&self) -> usize {
        self.origins.len()
    }

    pub fn views(&self) -> RayViews<'_> {
        RayViews {
            origins: self.origins.view(),
            directions: self.directions.view(),
            tmin: self.tmin.as_array(),
            tmax: self.tmax.as_array(),
            len: self.len(),
        }
    }
}

/// Rays per task when rays are built in parallel.
const CHUNK: usize = 8192;

impl RayViews<'_> {
    /// Ray `i`, or why it cannot be traced.
    fn ray(&self, i: usize) -> Result<Ray, String> {
        let org = self.origins.row(i);
        let dir = self.directions.row(i);
        let (tmin, tmax) = (self.tmin[i], self.tmax[i]);
        if !org.iter().all(|c| c.is_finite()) {
            return Err(format!("ray {i}: the origin {org:?} is not finite (in float32)"));
        }
        if !dir.iter().all(|c| c.is_finite()) {
            return Err(format!("ray {i}: the direction {dir:?} is not finite (in float32)"));
        }
        if dir.iter().all(|&c| c == 0.0) {
            return Err(format!("ray {i}: the direction is zero"));
        }
        if tmin.is_nan() || tmax.is_nan() {
            return Err(format!("ray {i}: tmin = {tmin}, tmax = {tmax}: NaN"));
        }
        if tmin > tmax {
            return Err(format!("ray {i}: tmin = {tmin} is greater than tmax = {tmax}"));
        }
        Ok(Ray::with_interval(org, dir, tmin, tmax))
    }

    /// Every ray, checked; on several threads if `parallel` (inside the caller's pool).
    pub fn rays(&self, parallel: bool) -> Result<Vec<Ray>, String> {
        let mut out = vec![Ray::new([0.0; 3], [0.0, 0.0, 1.0]); self.len];
        let fill = |(c, chunk): (usize, &mut [Ray])| -> Result<(), String> {
            for (k, r) in chunk.iter_mut().enumerate() {
                *r = self.ray(c * CHUNK + k)?;
            }
            Ok(())
        };
        if parallel {
            // The first bad ray by index, whichever thread met it.
            let errors: Vec<(usize, String)> = out
                .par_chunks_mut(CHUNK)
                .enumerate()
                .filter_map(|(c, chunk)| fill((c, chunk)).err().map(|e| (c, e)))
                .collect();
            if let Some((_, e)) = errors.into_iter().min_by_key(|(c, _)| *c) {
                return Err(e);
            }
        } else {
            out.chunks_mut(CHUNK).enumerate().try_for_each(fill)?;
        }
        Ok(out)
    }
}
