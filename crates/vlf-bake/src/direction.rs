//! The per-direction kernel of a bake: `vlf-raster`'s [`build_direction`](vlf_raster::build_direction)
//! over a prepared scene with the bake's parameters, its overflow named as a [`BakeError`].

use crate::error::BakeError;
use crate::params::Params;
use crate::prepare::Prepared;
use vlf_raster::DirectionError;
pub use vlf_raster::{DirectionData, Scratch};

/// Builds direction `j` (rotation `m`): its TILES entries, its blocks and statistics.
pub fn build_direction(
    prep: &Prepared<'_>,
    params: &Params,
    m: &[f64; 9],
    j: usize,
    s: &mut Scratch,
) -> Result<DirectionData, BakeError> {
    vlf_raster::build_direction(&prep.vertices, &prep.triangles, &params.grid(prep.radius), m, s).map_err(|e| match e {
        DirectionError::TooLarge(e) => {
            BakeError::DirectionTooLarge { direction: j, count: e.count, what: "words of tile blocks" }
        }
        DirectionError::OutOfMemory { bytes } => BakeError::OutOfMemory { direction: j, bytes, tiles: params.tiles },
    })
}
