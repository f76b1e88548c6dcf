//! The paper's experiments (§6), reproduced on this machine: the visibility field against a
//! single-ray CRT kd-tree, both answering the same rays with the same triangle kernel in the same
//! process, so a ratio measures the acceleration structures and nothing else.
//!
//! - [`experiments::figure3`]: frame time of a 512×512 image of unshaded primary rays against the
//!   number of triangles, from outside and from inside, for CRT at its best depth and leaf size (a
//!   sweep, as the paper did), and the field with linear tiles and with 1D-BSP tiles at 32², 64²
//!   and 128².
//! - [`experiments::figure4`]: a walkthrough of the 16K scene, outside to inside: frame time and
//!   triangle tests per frame for both.
//! - [`experiments::parameters`]: frame time, field size and bake time against directions, tiles
//!   and the BSP policy for the 100K scene.
//! - [`first_pixel`]: time to first pixel (open a field and trace one ray, in a new process) for
//!   fields of any size, with the file in the page cache and evicted from it.
//! - [`peers`]: the field against Embree, obvhs and the kd-tree on the same scenes and rays
//!   (issue 12), every contestant's hits checked against the brute force.
//!
//! - [`dynamic`]: dynamic scenes (issue 13): instances against Embree's two-level instancing,
//!   per-frame transform updates, and the paper's delete and reinsert.
//! - [`latency`]: what one dependent load to memory costs, which the peers benchmark records
//!   before each ray set.
//!
//! Frames are traced on one thread (the paper used one processor); every timing is the median of
//! `repeats` runs after a warm-up run. Bakes use all cores.

// Only `first_pixel` needs `unsafe`: it maps fields and asks the kernel which pages are cached.
#![deny(unsafe_code)]

pub mod dynamic;
pub mod experiments;
#[allow(unsafe_code)]
pub mod first_pixel;
pub mod latency;
pub mod peers;
pub mod plot;

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_bake::{BakeConfig, NoProgress, Prepared, Scene};
use vlf_geom::{Hit, Ray};
use vlf_runtime::Field;

/// Settings shared by all experiments.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Where fields are baked (and deleted after use).
    pub work: PathBuf,
    /// Where tables, plots and raw JSON go.
    pub out: PathBuf,
    /// Timed runs per measurement, after one warm-up run.
    pub repeats: usize,
    /// Image width and height of a frame.
    pub resolution: u32,
    /// Largest field the experiments bake.
    pub max_field_bytes: u64,
    /// Print progress lines.
    pub verbose: bool,
}

/// The median of `v` (which it sorts).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Timed runs of one frame and their median.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Timing {
    pub median_s: f64,
    pub runs_s: Vec<f64>,
}

/// Traces `rays` once on this thread; returns seconds and a checksum of the answers.
pub fn trace_once(rays: &[Ray], mut trace: impl FnMut(&Ray) -> Option<Hit>) -> (f64, u64) {
    let start = Instant::now();
    let mut sum = 0u64;
    for r in rays {
        if let Some(h) = trace(black_box(r)) {
            sum = sum.wrapping_add(h.t.to_bits() as u64 ^ h.prim as u64);
        }
    }
    (start.elapsed().as_secs_f64(), black_box(sum))
}

/// One warm-up run, then `repeats` timed runs.
pub fn measure(rays: &[Ray], repeats: usize, mut trace: impl FnMut(&Ray) -> Option<Hit>) -> Timing {
    trace_once(rays, &mut trace);
    let mut runs: Vec<f64> = (0..repeats.max(1)).map(|_| trace_once(rays, &mut trace).0).collect();
    let runs_s = runs.clone();
    Timing { median_s: median(&mut runs), runs_s }
}

/// Bitwise disagreements in closest-hit `t` between two answer lists (a sanity check: both methods
/// use the same kernel, so a correct pair agrees exactly).
pub fn disagreements(a: &[Option<Hit>], b: &[Option<Hit>]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(x, y)| match (x, y) {
            (None, None) => false,
            (Some(x), Some(y)) => x.t.to_bits() != y.t.to_bits(),
            _ => true,
        })
        .count()
}

/// A baked field and what it cost.
pub struct Baked {
    pub field: Field,
    pub path: PathBuf,
    pub seconds: f64,
    pub bytes: u64,
    pub directions: u32,
    pub tiles: u32,
}

impl Drop for Baked {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Why a configuration was not baked.
#[derive(Debug)]
pub enum Skipped {
    OverBudget(String),
}

/// Bakes `scene` with `config` into `work/name.vlf` (all cores), or says why not.
pub fn bake(scene: &Scene, config: &BakeConfig, work: &Path, name: &str) -> anyhow::Result<Result<Baked, Skipped>> {
    std::fs::create_dir_all(work)?;
    let path = work.join(format!("{name}.vlf"));
    let start = Instant::now();
    let prep = Prepared::new(scene);
    let choice = match vlf_bake::choose(&prep, config) {
        Ok(c) => c,
        Err(vlf_bake::BakeError::Params(why)) => return Ok(Err(Skipped::OverBudget(why.to_string()))),
        Err(e) => return Err(e.into()),
    };
    let summary = match vlf_bake::writer::write_field(&prep, &choice, &config.request(), &path, &NoProgress) {
        Ok(s) => s,
        Err(e @ vlf_bake::BakeError::OverBudget { .. }) => return Ok(Err(Skipped::OverBudget(e.to_string()))),
        Err(e) => return Err(e.into()),
    };
    let seconds = start.elapsed().as_secs_f64();
    let field = Field::open(&path)?;
    Ok(Ok(Baked {
        field,
        path,
        seconds,
        bytes: summary.bytes,
        directions: summary.directions,
        tiles: summary.tile_resolution,
    }))
}

/// Writes `contents` to `out/name`, creating `out`.
pub fn write_output(out: &Path, name: &str, contents: &str) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(out)?;
    let path = out.join(name);
    std::fs::write(&path, contents)?;
    Ok(path)
}

/// Mean and coefficient of variation (standard deviation over mean).
pub fn mean_cv(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (mean, var.sqrt() / mean)
}
