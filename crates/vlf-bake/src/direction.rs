//! The per-direction kernel of a bake: `vlf-raster`'s [`build_direction`](vlf_raster::build_direction)
//! over a prepared scene with the bake's parameters, its overflow named as a [`BakeError`].

use crate::error::BakeError;
use crate::params::{Params, human_bytes};
use crate::prepare::Prepared;
use std::sync::atomic::AtomicU64;
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
    limit: Limit<'_>,
) -> Result<DirectionData, BakeError> {
    let grid = params.grid(prep.radius);
    let (v, t) = (&prep.vertices, &prep.triangles);
    vlf_raster::build_direction(v, t, &grid, m, s, limit.words, limit.shared).map_err(|e| match e {
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

/// How many words a direction's blocks may take, and why (for the message); and, if `shared`, a
/// pool of words that the directions built at the same time draw on together
/// ([`vlf_raster::build_direction`]).
#[derive(Clone, Copy, Debug)]
pub struct Limit<'a> {
    pub words: u64,
    pub why: &'static str,
    pub shared: Option<&'a AtomicU64>,
}

impl Limit<'_> {
    /// The format's limit only.
    pub const FORMAT: Limit<'static> =
        Limit { words: vlf_raster::MAX_WORDS, why: "the format's 32-bit offsets", shared: None };

    /// `words`, for the reason `why`, with no pool.
    pub fn new(words: u64, why: &'static str) -> Limit<'static> {
        Limit { words, why, shared: None }
    }

    /// The words a thread of `threads` may hold while it bakes a direction: the memory budget
    /// ([`crate::memory::budget`]) shared by the threads, each block's word held twice (in its
    /// leaf's list, then in the direction's words).
    pub fn memory(threads: usize) -> Limit<'static> {
        let words = crate::memory::budget().0 / threads.max(1) as u64 / 16;
        Limit::new(words, "its share of the memory that may be used").min(Limit::FORMAT)
    }
}

impl<'a> Limit<'a> {
    /// The smaller of the two, with the pool of either.
    pub fn min(self, other: Limit<'a>) -> Limit<'a> {
        let shared = self.shared.or(other.shared);
        Limit { shared, ..if other.words < self.words { other } else { self } }
    }

    /// This limit, its directions also drawing on `pool`.
    pub fn sharing(self, pool: &AtomicU64) -> Limit<'_> {
        Limit { shared: Some(pool), ..self }
    }
}
