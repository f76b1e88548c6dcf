//! Import triangle meshes (OBJ, glTF) and bake them into VLF visibility-field files
//! (`formats/vlf.md`). The `vlf-bake` command line (the `vlf-cli` package) is a thin layer over
//! this library.
//!
//! ```no_run
//! use vlf_bake::{BakeConfig, NoProgress, bake_scene, import::import_paths};
//!
//! let scene = import_paths(&["fixtures/meshes/bunny.obj"])?;
//! let summary = bake_scene(&scene, &BakeConfig::default(), "bunny.vlf".as_ref(), &NoProgress)?;
//! println!("{} directions × {}² tiles, {} bytes", summary.directions, summary.tile_resolution, summary.bytes);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A bake reads, in order: [`import`] (meshes to a [`Scene`]), [`prepare`] (the bounding sphere
//! and indexed triangles), [`params`] (the parameters, measured through [`estimate`]),
//! [`sections`] (the shared sections and the input hash), [`writer`] (every direction through
//! the [`direction`] kernel, written in order) and [`atomic`] (the rename into place).
//! `docs/architecture.md` has the module map.

#![forbid(unsafe_code)]

pub mod atomic;
pub mod cache;
pub mod direction;
pub mod disk;
pub mod error;
pub mod estimate;
pub mod floor;
pub mod generate;
pub mod import;
pub mod inspect;
pub mod job;
pub mod memory;
pub mod order;
pub mod pack;
pub mod params;
pub mod prepare;
pub mod progress;
pub mod report;
pub mod scene;
pub mod sections;
pub mod shard;
pub mod statistics;
pub mod writer;

pub use error::BakeError;
pub use params::{BakeConfig, Choice, DepthPolicy, Params, ParamsError, choose};
pub use prepare::Prepared;
pub use progress::{NoProgress, Progress};
pub use scene::{ImportError, ImportReport, MaterialDesc, Scene, SceneBuilder, SourceDesc};
pub use sections::{BAKER_REVISION, input_hash};
pub use statistics::Statistics;
pub use writer::BakeSummary;

/// Chooses parameters for `config` and bakes `scene` into `output` (atomically): the library's
/// one call for a whole bake.
pub fn bake_scene(
    scene: &Scene,
    config: &BakeConfig,
    output: &std::path::Path,
    progress: &dyn Progress,
) -> Result<BakeSummary, BakeError> {
    let prep = Prepared::new(scene);
    let choice = choose(&prep, config)?;
    writer::write_field(&prep, &choice, &config.request(), output, progress)
}
