//! The per-direction kernel of a bake: `vlf-raster`'s [`build_direction`](vlf_raster::build_direction)
//! over a prepared scene with the bake's parameters, its overflow named as a [`BakeError`].

use crate::error::BakeError;
use crate::params::{Params, human_bytes};
use crate::prepare::Prepared;
use vlf_raster::DirectionError;
pub use vlf_raster::{DirectionData, Scratch};

/// Builds direction `j` (rotation `m`): its TILES entries, its blocks and statistics; its blocks
/// may take at most `limit` words (and the format's [`vlf_raster::MAX_WORDS`]).
pub fn build_direction(
    prep: &Prepared<'_>,
    params: &Params,
    m: &[f64; 9],
    j: usize,
    s: &mut Scratch,
    limit: Limit,
) -> Result<DirectionData, BakeError> {
    let grid = params.grid(prep.radius);
    vlf_raster::build_direction(&prep.vertices, &prep.triangles, &grid, m, s, limit.words).map_err(|e| match e {
        DirectionError::TooLarge(e) if e.limit < vlf_raster::MAX_WORDS => BakeError::DirectionOverLimit {
            direction: j,
            limit: human_bytes(e.limit.saturating_mul(8)),
            why: limit.why,
        },
        DirectionError::TooLarge(e) => {
            BakeError::DirectionTooLarge { direction: j, count: e.count, what: "words of tile blocks" }
        }
        DirectionError::OutOfMemory { bytes } => BakeError::OutOfMemory { direction: j, bytes, tiles: params.tiles },
    })
}

/// How many words a direction's blocks may take, and why (for the message).
#[derive(Clone, Copy, Debug)]
pub struct Limit {
    pub words: u64,
    pub why: &'static str,
}

impl Limit {
    /// The format's limit only.
    pub const FORMAT: Limit = Limit { words: vlf_raster::MAX_WORDS, why: "the format's 32-bit offsets" };

    /// The words a thread of `threads` may hold while it bakes a direction: the memory budget
    /// ([`crate::memory::budget`]) shared by the threads, each block's word held twice (in its
    /// leaf's list, then in the direction's words).
    pub fn memory(threads: usize) -> Limit {
        let words = crate::memory::budget().0 / threads.max(1) as u64 / 16;
        Limit { words, why: "its share of the memory that may be used" }.min(Limit::FORMAT)
    }

    /// The smaller of the two.
    pub fn min(self, other: Limit) -> Limit {
        if other.words < self.words { other } else { self }
    }
}
