//! Bakes from Python: mesh files through the command line's own job (`vlf_bake::job`: import,
//! cache, bake, store), and triangle arrays through the same steps on a scene built in memory.
//! Both take the command line's options and its cache directory (`cache_dir`, else
//! `VLF_CACHE_DIR`), release the GIL, and run on the pool the `threads` argument names.

use crate::errors::{BakeError, io_error, value_error};
use crate::field::Field;
use crate::threads::Threads;
use numpy::PyReadonlyArray3;
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_bake::cache::{Cache, Lookup, key_for_scene};
use vlf_bake::job::{BakeJob, JobError, run_bake_job};
use vlf_bake::{BakeConfig, DepthPolicy, ImportError, NoProgress, Prepared, Scene, choose};

/// The options every bake takes (the command line's `bake` flags).
struct Options {
    config: BakeConfig,
    cache: Option<Cache>,
    /// Why the cache is not used, if it is not.
    cache_note: Option<String>,
    threads: Threads,
}

#[allow(clippy::too_many_arguments)]
fn options(
    directions: Option<u32>,
    tiles: Option<u32>,
    leaf_size: Option<u32>,
    max_depth: Option<u32>,
    max_bytes: Option<u64>,
    max_bytes_per_triangle: Option<u64>,
    cache_dir: Option<PathBuf>,
    no_cache: bool,
    threads: Option<usize>,
) -> PyResult<Options> {
    let defaults = BakeConfig::default();
    let config = BakeConfig {
        directions,
        tiles,
        depth: DepthPolicy {
            leaf_size: leaf_size.unwrap_or(defaults.depth.leaf_size),
            max_depth: max_depth.unwrap_or(defaults.depth.max_depth),
        },
        max_bytes: max_bytes.unwrap_or(defaults.max_bytes),
        max_bytes_per_triangle: max_bytes_per_triangle.unwrap_or(defaults.max_bytes_per_triangle),
    };
    config.validate().map_err(|e| value_error(e.to_string()))?;
    let (cache, cache_note) = match vlf_bake::cache::resolve(cache_dir, no_cache, "no_cache=True", "cache_dir") {
        Ok(Ok(cache)) => (Some(cache), None),
        Ok(Err(note)) | Err(note) => (None, Some(note)),
    };
    Ok(Options { config, cache, cache_note, threads: Threads::new(threads)? })
}

fn import_error(e: ImportError) -> PyErr {
    match &e {
        ImportError::Io { error, .. } => io_error(error.kind(), e.to_string()),
        _ => BakeError::new_err(e.to_string()),
    }
}

fn job_error(e: JobError) -> PyErr {
    match e {
        JobError::Import(e) => import_error(e),
        JobError::Io { ref error, .. } => io_error(error.kind(), e.to_string()),
        other => BakeError::new_err(other.to_string()),
    }
}

/// What a bake did, for `Field.bake_info`.
struct Info {
    cache: &'static str,
    cache_note: Option<String>,
    seconds: f64,
    triangles: u64,
    dropped_degenerate: u64,
    dropped_duplicates: u64,
    choice: String,
    warnings: Vec<String>,
}

impl Info {
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("cache", self.cache)?;
        d.set_item("cache_note", &self.cache_note)?;
        d.set_item("seconds", self.seconds)?;
        d.set_item("triangles", self.triangles)?;
        d.set_item("dropped_degenerate", self.dropped_degenerate)?;
        d.set_item("dropped_duplicates", self.dropped_duplicates)?;
        d.set_item("choice", &self.choice)?;
        d.set_item("warnings", &self.warnings)?;
        Ok(d)
    }
}

/// Bakes mesh files (OBJ, glTF, GLB) into the field `output`, as `vlf-bake bake` does, and opens
/// it: `(Field, info)`.
#[pyfunction]
#[pyo3(signature = (inputs, output, directions=None, tiles=None, leaf_size=None, max_depth=None,
    max_bytes=None, max_bytes_per_triangle=None, cache_dir=None, no_cache=false, threads=None))]
#[allow(clippy::too_many_arguments)]
pub fn bake_files<'py>(
    py: Python<'py>,
    inputs: Vec<PathBuf>,
    output: PathBuf,
    directions: Option<u32>,
    tiles: Option<u32>,
    leaf_size: Option<u32>,
    max_depth: Option<u32>,
    max_bytes: Option<u64>,
    max_bytes_per_triangle: Option<u64>,
    cache_dir: Option<PathBuf>,
    no_cache: bool,
    threads: Option<usize>,
) -> PyResult<(Field, Bound<'py, PyDict>)> {
    if inputs.is_empty() {
        return Err(value_error("no input files: give at least one mesh (.obj, .gltf, .glb)"));
    }
    let o = options(
        directions,
        tiles,
        leaf_size,
        max_depth,
        max_bytes,
        max_bytes_per_triangle,
        cache_dir,
        no_cache,
        threads,
    )?;
    let Options { config, cache, cache_note, threads } = o;
    let (out, field) = py
        .detach(|| {
            threads.run(|| {
                // Built here: a job is not `Sync` (its `on_choice` callback), so it cannot cross.
                let job = BakeJob {
                    inputs: &inputs,
                    output: &output,
                    config,
                    shard: None,
                    cache,
                    cache_note,
                    on_choice: None,
                };
                let out = run_bake_job(&job, &NoProgress).map_err(Failure::Job)?;
                let field = vlf_runtime::Field::open(&output).map_err(Failure::Open)?;
                Ok((out, field))
            })
        })
        .map_err(Failure::into_py)?;
    let info = Info {
        cache: if out.cache_hit.is_some() { "hit" } else { out.report.cache.status },
        cache_note: out.report.cache.note.clone(),
        seconds: out.summary.seconds,
        triangles: out.summary.triangles,
        dropped_degenerate: out.summary.dropped_degenerate,
        dropped_duplicates: out.summary.dropped_duplicates,
        choice: out.summary.choice.clone(),
        warnings: out.import.warnings.iter().chain(&out.warnings).cloned().collect(),
    };
    Ok((Field::new(field, Some(output)), info.to_dict(py)?))
}

/// A failure with the GIL released, turned into a Python exception once it is held again.
enum Failure {
    Job(JobError),
    Import(ImportError),
    Bake(vlf_bake::BakeError),
    Open(vlf_runtime::OpenError),
    Io(PathBuf, std::io::Error),
}

impl Failure {
    fn into_py(self) -> PyErr {
        match self {
            Failure::Job(e) => job_error(e),
            Failure::Import(ImportError::NonFinite { triangle, vertex, value, .. }) => {
                value_error(format!("triangle {triangle}: vertex {vertex} has a non-finite coordinate {value:?}"))
            }
            Failure::Import(ImportError::NoTriangles { .. }) => {
                value_error("no triangles to bake: every face has zero area, or there are none")
            }
            Failure::Import(e) => import_error(e),
            Failure::Bake(vlf_bake::BakeError::Io { path, error }) => {
                io_error(error.kind(), format!("cannot write {}: {error}", path.display()))
            }
            Failure::Bake(e) => BakeError::new_err(e.to_string()),
            Failure::Open(e) => crate::errors::open_error(e),
            Failure::Io(path, e) => io_error(e.kind(), format!("{}: {e}", path.display())),
        }
    }
}

/// Bakes a scene of triangles (world coordinates, one source named `name`; triangle `i` of the
/// array has provenance index `i`) into `output`, through the cache.
fn bake_scene(scene: &Scene, options: &Options, output: &Path) -> Result<Info, Failure> {
    let started = Instant::now();
    let prep = Prepared::new(scene);
    let request = options.config.request();
    let mut info = Info {
        cache: if options.cache.is_some() { "miss" } else { "disabled" },
        cache_note: options.cache_note.clone(),
        seconds: 0.0,
        triangles: prep.scene.triangles.len() as u64,
        dropped_degenerate: scene.report.dropped_degenerate,
        dropped_duplicates: scene.report.dropped_duplicates,
        choice: String::new(),
        warnings: scene.report.warnings.clone(),
    };
    let key = options.cache.as_ref().map(|_| key_for_scene(&prep, &request));
    if let (Some(cache), Some(key)) = (&options.cache, &key) {
        match cache.lookup(key, output).map_err(|e| Failure::Io(output.to_path_buf(), e))? {
            Lookup::Hit(_) => {
                info.cache = "hit";
                info.choice = format!("copied from the cache entry {}", cache.entry_path(key).display());
                info.seconds = started.elapsed().as_secs_f64();
                return Ok(info);
            }
            Lookup::Miss => {}
            Lookup::Unusable { problem } => info.warnings.push(problem),
        }
    }
    let choice = choose(&prep, &options.config).map_err(Failure::Bake)?;
    info.choice = choice.reason.clone();
    vlf_bake::writer::write_field(&prep, &choice, &request, output, &NoProgress).map_err(Failure::Bake)?;
    if let (Some(cache), Some(key)) = (&options.cache, &key) {
        let stored = std::fs::File::open(output).and_then(|f| cache.store(key, &f));
        if let Err(e) = stored {
            info.warnings.push(format!("cannot store the field in the cache {}: {e}", cache.root().display()));
        }
    }
    info.seconds = started.elapsed().as_secs_f64();
    Ok(info)
}

/// Bakes triangles `(F, 3, 3)` (float64, world coordinates) into a field: written to `output`
/// and mapped, or, without `output`, baked in a temporary directory and read into memory.
/// Returns `(Field, info)`.
#[pyfunction]
#[pyo3(signature = (triangles, name, output=None, directions=None, tiles=None, leaf_size=None,
    max_depth=None, max_bytes=None, max_bytes_per_triangle=None, cache_dir=None, no_cache=false,
    threads=None))]
#[allow(clippy::too_many_arguments)]
pub fn bake_triangles<'py>(
    py: Python<'py>,
    triangles: PyReadonlyArray3<'py, f64>,
    name: String,
    output: Option<PathBuf>,
    directions: Option<u32>,
    tiles: Option<u32>,
    leaf_size: Option<u32>,
    max_depth: Option<u32>,
    max_bytes: Option<u64>,
    max_bytes_per_triangle: Option<u64>,
    cache_dir: Option<PathBuf>,
    no_cache: bool,
    threads: Option<usize>,
) -> PyResult<(Field, Bound<'py, PyDict>)> {
    let shape = triangles.shape();
    if shape[1] != 3 || shape[2] != 3 {
        return Err(value_error(format!("`triangles` must have shape (F, 3, 3), not {shape:?}")));
    }
    let o = options(
        directions,
        tiles,
        leaf_size,
        max_depth,
        max_bytes,
        max_bytes_per_triangle,
        cache_dir,
        no_cache,
        threads,
    )?;
    let view = triangles.as_array();
    let result = py.detach(|| {
        o.threads.run(|| -> Result<(Info, vlf_runtime::Field), Failure> {
            let tris: Vec<[[f64; 3]; 3]> =
                view.outer_iter().map(|t| std::array::from_fn(|v| std::array::from_fn(|k| t[[v, k]]))).collect();
            let scene = Scene::from_triangles_f64(&name, &tris).map_err(Failure::Import)?;
            match &output {
                Some(path) => {
                    let info = bake_scene(&scene, &o, path)?;
                    Ok((info, vlf_runtime::Field::open(path).map_err(Failure::Open)?))
                }
                None => {
                    let dir = tempfile::tempdir().map_err(|e| Failure::Io(std::env::temp_dir(), e))?;
                    let path = dir.path().join("field.vlf");
                    let info = bake_scene(&scene, &o, &path)?;
                    Ok((info, vlf_runtime::Field::read(&path).map_err(Failure::Open)?))
                }
            }
        })
    });
    let (info, field) = result.map_err(Failure::into_py)?;
    Ok((Field::new(field, output), info.to_dict(py)?))
}
