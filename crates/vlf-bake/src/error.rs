//! Why a bake failed: [`BakeError`], one variant per fault, each naming what it is about.

use crate::params::ParamsError;
use std::io;
use std::path::PathBuf;

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BakeError {
    #[error("cannot write {path}: {error}")]
    Io { path: PathBuf, error: io::Error },
    /// The parameters asked for are out of range, or cannot fit the size budget.
    #[error(transparent)]
    Params(#[from] ParamsError),
    #[error(
        "direction {direction} needs {count} {what}, more than the format's 2^32 - 1 per direction; lower --tiles or the scene size"
    )]
    DirectionTooLarge { direction: usize, count: u64, what: &'static str },
    /// Explicit parameters produced more bytes than `--max-bytes` allows; the bake stopped as soon
    /// as it knew, and removed what it had written.
    #[error(
        "the field outgrew the --max-bytes ceiling of {ceiling} bytes ({at_least} bytes or more after {baked} of {directions} directions); lower --directions or --tiles, or raise --max-bytes"
    )]
    OverBudget { ceiling: u64, at_least: u64, baked: usize, directions: usize },
    /// A direction's tile blocks grew past what it may take: long triangles on fine tiles land
    /// in many tiles, and in many leaves of each.
    #[error(
        "direction {direction}'s tile blocks pass the {limit} a direction may take ({why}); lower --tiles or --directions, or --threads"
    )]
    DirectionOverLimit { direction: usize, limit: String, why: &'static str },
    /// A direction's buffers (a few bytes per tile) could not be allocated.
    #[error(
        "direction {direction} needs {bytes} bytes more for its {tiles} × {tiles} tiles, which cannot be allocated; lower --tiles or --threads"
    )]
    OutOfMemory { direction: usize, bytes: u64, tiles: u32 },
    /// The bake's buffers for its directions would not fit the memory this machine has free
    /// (checked before any work).
    #[error(
        "baking {tiles} × {tiles} tiles on {threads} thread(s) needs about {need} of memory (a direction's buffers take about {per_tile} bytes a tile and {per_entry} bytes for each of its triangle-tile pairs, {entries} or more in the largest direction, on each thread; its direction tables {tables}), but {allowed}; lower --tiles, --threads or --directions"
    )]
    NotEnoughMemory {
        tiles: u32,
        threads: usize,
        per_tile: u64,
        per_entry: u64,
        entries: u64,
        tables: String,
        need: String,
        allowed: String,
    },
    /// The field would not fit the free space of the file system it goes to (checked before the
    /// directions are baked).
    #[error(
        "the {what} {needs} but the file system of {} has {free} free; free some space, write it elsewhere, or lower --directions, --tiles or --max-bytes",
        dir.display()
    )]
    NotEnoughDisk { what: &'static str, needs: String, dir: PathBuf, free: String },
}
