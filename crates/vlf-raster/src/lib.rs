//! The kernel that puts triangles into a visibility field's directions: conservative
//! rasterisation into one direction's tile grid ([`raster`], paper §3.2), the leaves of a tile
//! ([`leaves`], paper §4 and §7) and the tile blocks of `formats/vlf.md` §5.6 built from them
//! ([`direction`]).
//!
//! Two users share it, so that a triangle lands in the same tiles, leaves and boxes whichever
//! put it there: `vlf-bake`, which bakes every direction of a field, and `vlf-scene`, which
//! inserts triangles into a mapped field in memory (the paper's §7 edits). No I/O, no threads:
//! the caller owns both.

#![forbid(unsafe_code)]

pub mod coverage;
pub mod direction;
pub mod leaves;
pub mod raster;

pub use coverage::Areas;
pub use direction::{
    DirectionData, DirectionError, Entry, Grid, MAX_WORDS, Scratch, TileBlock, TooLarge, build_direction,
};
pub use leaves::{DEFAULT_LEAF_SIZE, DEFAULT_MAX_DEPTH, DepthPolicy};
