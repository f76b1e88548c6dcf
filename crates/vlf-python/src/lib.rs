//! `vlf._vlf`: the native module of the `vlf` Python package (`python/vlf`), over the VLF
//! runtime and baker. The Python layer normalises arguments (dtypes, broadcasting of `tmin` and
//! `tmax`) and names the results; this module checks shapes and values, releases the GIL and
//! runs the queries on a thread pool.
//!
//! - `field`: the `Field` class (open, metadata, queries).
//! - `rays`: numpy arrays (f32 or f64, any strides) to rays, checked.
//! - `bake`: bakes from mesh files and from triangle arrays, through the bake cache.
//! - `threads`: the `threads` argument as a rayon pool.
//! - `errors`: the package's exceptions and how Rust errors map to Python's.

mod bake;
mod errors;
mod field;
mod rays;
mod threads;

use pyo3::prelude::*;

/// The module's contents.
#[pymodule]
fn _vlf(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<field::Field>()?;
    m.add_function(wrap_pyfunction!(bake::bake_files, m)?)?;
    m.add_function(wrap_pyfunction!(bake::bake_triangles, m)?)?;
    m.add("FieldError", py.get_type::<errors::FieldError>())?;
    m.add("BakeError", py.get_type::<errors::BakeError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
