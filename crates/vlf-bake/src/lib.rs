//! Import triangle meshes (OBJ, glTF) and bake them into VLF visibility-field files
//! (`formats/vlf.md`). The `vlf-bake` binary is a thin command line over this library.
//!
//! ```no_run
//! use vlf_bake::{BakeConfig, NoProgress, bake_scene, import::import_paths};
//!
//! let scene = import_paths(&["fixtures/meshes/bunny.obj"])?;
//! let summary = bake_scene(&scene, &BakeConfig::default(), "bunny.vlf".as_ref(), &NoProgress)?;
//! println!("{} directions × {}² tiles, {} bytes", summary.directions, summary.tile_resolution, summary.bytes);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bake;
pub mod cache;
pub mod generate;
pub mod import;
pub mod inspect;
pub mod job;
pub mod pack;
pub mod params;
pub mod raster;
pub mod report;
pub mod scene;
pub mod shard;

pub use bake::{BAKER_REVISION, BakeError, BakeSummary, NoProgress, Prepared, Progress, Statistics, input_hash};
pub use params::{BakeConfig, Choice, DepthPolicy, Params, choose};
pub use scene::{ImportError, ImportReport, MaterialDesc, Scene, SceneBuilder, SourceDesc};

/// Chooses parameters for `config` and bakes `scene` into `output` (atomically).
pub fn bake_scene(
    scene: &Scene,
    config: &BakeConfig,
    output: &std::path::Path,
    progress: &dyn Progress,
) -> Result<BakeSummary, BakeError> {
    let prep = Prepared::new(scene);
    let choice = choose(&prep, config)?;
    bake::bake_to_path(&prep, &choice, &config.request(), output, progress)
}
