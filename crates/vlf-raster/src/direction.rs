//! The per-direction kernel (paper §3.1, §3.2, §4 and §5): rotate the triangles into one
//! direction's canonical frame, rasterise every triangle conservatively into the `n × n` tiles
//! with the box of its part in each ([`Grid::rasterize`]), cut each tile's z range into leaves
//! ([`crate::leaves`]) and write the tile's block (`formats/vlf.md` §5.6, [`Grid::write_tile`]).
//!
//! [`build_direction`] does all of it for every triangle of a scene (the bake); the parts are
//! public so that a field's tiles can be rebuilt one at a time in memory (`vlf-scene`'s edits).

use crate::leaves::{DepthPolicy, Slab, boundaries, leaf_cost, ref_weight};
use crate::raster::{Part, rasterize};
use std::sync::atomic::{AtomicU64, Ordering};
use vlf_format::block::{BOX_CELLS, MAX_LEAVES, Ref, block_words, write_block};
use vlf_format::{EMPTY_TILE, StatisticsRecord, Z_LEVELS, size};
use vlf_geom::frame::mul;

/// The tile grid of a field, as every one of its directions lays it out: what rasterising a
/// triangle into a direction needs besides the direction's rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Tiles per side, `n`.
    pub tiles: u32,
    /// The field's lattice size `N` (`2N² + 1` directions): with `tiles`, what visiting a leaf
    /// costs the leaves' heuristic ([`crate::leaves::leaf_cost`]).
    pub lattice_n: u32,
    /// The radius `R` of the bounding sphere the grid covers, around the field's centre.
    pub radius: f64,
    /// The conservative margin `μ` (`formats/vlf.md` §6.2), world units.
    pub margin: f64,
    /// How each tile's z range is cut into leaves.
    pub depth: DepthPolicy,
}

/// One rasterised (tile, triangle) pair: the triangle's z range in the tile in quantized levels
/// and its box in box cells (`x_lo, x_hi, y_lo, y_hi`), both grown by `μ` and rounded outward.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Entry {
    /// The tile, `row · n + column`.
    pub tile: u32,
    /// The triangle id.
    pub tri: u32,
    /// The z range, in quantized levels, closed.
    pub z: [u16; 2],
    /// The box: `x_lo, x_hi, y_lo, y_hi` in cells of the tile.
    pub cells: [u8; 4],
}

/// The size of a tile's block: its leaves `K` and refs `m` (a triangle counted once per leaf).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileBlock {
    pub leaves: usize,
    pub refs: u64,
}

/// A direction's blocks would pass `limit` words (the format's 32-bit offsets, or a caller's
/// limit on the memory they take): `count` words written or being written when it was known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooLarge {
    pub count: u64,
    pub limit: u64,
}

/// The most words a direction's blocks can take: the format's 32-bit offsets.
pub const MAX_WORDS: u64 = u32::MAX as u64;

/// Why [`build_direction`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectionError {
    /// The blocks would not fit the format's 32-bit offsets.
    TooLarge(TooLarge),
    /// A buffer of `bytes` bytes (one entry or more per tile, so `n²`-sized) could not be
    /// allocated: refused as an error, not an abort.
    OutOfMemory { bytes: u64 },
}

impl From<TooLarge> for DirectionError {
    fn from(e: TooLarge) -> Self {
        DirectionError::TooLarge(e)
    }
}

/// `v` cleared and holding room for `n` more items, or the bytes that could not be allocated.
fn reserve<T>(v: &mut Vec<T>, n: usize) -> Result<(), DirectionError> {
    v.clear();
    v.try_reserve_exact(n).map_err(|_| DirectionError::OutOfMemory { bytes: (n * size_of::<T>()) as u64 })
}

/// Reusable buffers: one per thread.
#[derive(Default)]
pub struct Scratch {
    projected: Vec<[f64; 3]>,
    entries: Vec<Entry>,
    sorted: Vec<Entry>,
    tile_start: Vec<u32>,
    slabs: Vec<Slab>,
    bounds: Vec<u32>,
    leaf_refs: Vec<Vec<Ref>>,
}

/// One direction's part of the TILES and LEAVES sections.
pub struct DirectionData {
    /// The `n²` TILES entries: each tile's block offset in `words`, or `EMPTY_TILE`.
    pub tiles: Vec<u32>,
    /// The direction's blocks, in tile order.
    pub words: Vec<u64>,
    pub stats: StatisticsRecord,
}

impl DirectionData {
    /// Bytes this direction adds to the file.
    pub fn bytes(&self) -> u64 {
        size::direction(self.tiles.len() as u64, self.words.len() as u64)
    }
}

impl Grid {
    /// The width of a tile, world units.
    pub fn tile_width(&self) -> f64 {
        2.0 * self.radius / self.tiles as f64
    }

    /// The canonical coordinates of `v` (relative to the field's centre) in the direction whose
    /// rotation is `m`: `(u, v)` in tile units from the grid's corner, `z` in world units.
    #[inline]
    pub fn project(&self, m: &[f64; 9], v: [f64; 3]) -> [f64; 3] {
        let (r, w) = (self.radius, self.tile_width());
        let p = mul(m, v);
        [(p[0] + r) / w, (p[1] + r) / w, p[2]]
    }

    /// Rasterises triangle `tri`, whose corners [`Grid::project`] gave as `a, b, c`: calls `emit`
    /// with its entry in every tile its projection touches, grown by the margin, row by row.
    #[inline]
    pub fn rasterize(&self, tri: u32, a: [f64; 3], b: [f64; 3], c: [f64; 3], mut emit: impl FnMut(Entry)) {
        let (n, r, margin) = (self.tiles, self.radius, self.margin);
        let e = margin / self.tile_width();
        let z_step = 2.0 * r / Z_LEVELS as f64;
        // Quantisation, rounding outward. (Casts truncate toward zero, which equals floor here
        // because negative values clamp to 0 anyway, and avoid a libm call.)
        let level_below = |z: f64| (((z + r) / z_step) as i64).clamp(0, Z_LEVELS as i64) as u16;
        let level_above = |z: f64| {
            let x = (z + r) / z_step;
            (x as i64 + ((x as i64 as f64) < x) as i64).clamp(0, Z_LEVELS as i64) as u16
        };
        let cell =
            |u: f64, tile: u32| (((u - tile as f64) * BOX_CELLS as f64) as i64).clamp(0, BOX_CELLS as i64 - 1) as u8;
        rasterize(a, b, c, n, e, |ix, iy, p: Part| {
            emit(Entry {
                tile: iy * n + ix,
                tri,
                z: [level_below(p.z.0 - margin), level_above(p.z.1 + margin)],
                cells: [cell(p.u.0 - e, ix), cell(p.u.1 + e, ix), cell(p.v.0 - e, iy), cell(p.v.1 + e, iy)],
            });
        });
    }

    /// Appends to `out` the block of a tile whose entries are `entries` (at least one, in
    /// increasing triangle id): its leaves by the depth policy, each ref in every leaf its z
    /// range meets. `TooLarge` if `out` would pass `limit` words (at most [`MAX_WORDS`], the
    /// format's 32-bit offsets), found while the refs are sorted into leaves: a tile of long
    /// triangles may put each in hundreds of leaves, and its refs take no more than the limit
    /// allows before it is refused.
    pub fn write_tile(
        &self,
        entries: &[Entry],
        s: &mut Scratch,
        out: &mut Vec<u64>,
        limit: u64,
    ) -> Result<TileBlock, TooLarge> {
        let limit = limit.min(MAX_WORDS);
        debug_assert!(!entries.is_empty() && entries.windows(2).all(|w| w[0].tri < w[1].tri));
        // The tile's z range, non-empty.
        s.slabs.clear();
        s.slabs.extend(
            entries.iter().map(|en| Slab { z: (en.z[0] as u32, en.z[1] as u32), weight: ref_weight(en.cells) }),
        );
        let lo = s.slabs.iter().map(|r| r.z.0).min().unwrap_or(0);
        let hi = s.slabs.iter().map(|r| r.z.1).max().unwrap_or(Z_LEVELS);
        let (lo, hi) = if lo < hi {
            (lo, hi)
        } else if hi < Z_LEVELS {
            (lo, hi + 1)
        } else {
            (lo - 1, hi)
        };
        boundaries(&s.slabs, lo, hi, &self.depth, leaf_cost(self.tiles, self.lattice_n), &mut s.bounds);
        let k = s.bounds.len() - 1;
        debug_assert!(k as u32 <= MAX_LEAVES);
        // Each ref goes to every leaf its closed range meets; entries are in id order, so each
        // leaf's refs are too.
        s.leaf_refs.resize_with(k.max(s.leaf_refs.len()), Vec::new);
        for leaf in &mut s.leaf_refs[..k] {
            leaf.clear();
        }
        let offset = out.len() as u64;
        let past = |refs: u64| offset + block_words(k, refs as usize) as u64 > limit;
        let mut refs = 0u64;
        for en in entries {
            let (z0, z1) = (en.z[0] as u32, en.z[1] as u32);
            let first = s.bounds[1..k].partition_point(|&b| b < z0);
            for (leaf, leaf_refs) in s.leaf_refs[first..k].iter_mut().enumerate() {
                if s.bounds[first + leaf] > z1 {
                    break;
                }
                leaf_refs.push(Ref { id: en.tri, x: [en.cells[0], en.cells[1]], y: [en.cells[2], en.cells[3]] });
                refs += 1;
            }
            if past(refs) {
                return Err(TooLarge { count: offset + block_words(k, refs as usize) as u64, limit });
            }
        }
        let bounds: Vec<u16> = s.bounds.iter().map(|&b| b as u16).collect();
        let leaves: Vec<&[Ref]> = s.leaf_refs[..k].iter().map(|l| l.as_slice()).collect();
        write_block(&bounds, &leaves, out);
        Ok(TileBlock { leaves: k, refs })
    }
}

/// Builds the direction whose rotation is `m` over `triangles` (three indices each into
/// `vertices`, which are relative to the field's centre): its TILES entries, its blocks and
/// statistics. A triangle's id is its index in `triangles`. `TooLarge` if its blocks would pass
/// `limit` words ([`Grid::write_tile`]) or, with a `shared` pool, the words left in it: each
/// block's words are taken from the pool as it is written, so that directions built at the same
/// time stop once together they pass what the pool held (checked a tile at a time).
pub fn build_direction(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    grid: &Grid,
    m: &[f64; 9],
    s: &mut Scratch,
    limit: u64,
    shared: Option<&AtomicU64>,
) -> Result<DirectionData, DirectionError> {
    let n2 = grid.tiles as usize * grid.tiles as usize;
    s.projected.clear();
    s.projected.extend(vertices.iter().map(|&v| grid.project(m, v)));
    s.entries.clear();
    for (id, tri) in triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|k| s.projected[k as usize]);
        let entries = &mut s.entries;
        grid.rasterize(id as u32, a, b, c, |en| entries.push(en));
    }

    // Counting sort by tile; stable, so each tile's entries stay in triangle-id order.
    // The `n²`-sized buffers are reserved fallibly: a grid too fine for memory is an error.
    reserve(&mut s.tile_start, n2 + 1)?;
    s.tile_start.resize(n2 + 1, 0);
    for en in &s.entries {
        s.tile_start[en.tile as usize + 1] += 1;
    }
    for i in 0..n2 {
        s.tile_start[i + 1] += s.tile_start[i];
    }
    s.sorted.clear();
    s.sorted.resize(s.entries.len(), Entry::default());
    {
        let mut cursor = Vec::new();
        reserve(&mut cursor, n2 + 1)?;
        cursor.extend_from_slice(&s.tile_start);
        for en in &s.entries {
            let slot = &mut cursor[en.tile as usize];
            s.sorted[*slot as usize] = *en;
            *slot += 1;
        }
    }

    let mut out = DirectionData { tiles: Vec::new(), words: Vec::new(), stats: StatisticsRecord::zeroed_record() };
    reserve(&mut out.tiles, n2)?;
    reserve(&mut out.words, s.entries.len() + n2)?;
    out.stats.tile_count = n2 as u64;
    let sorted = std::mem::take(&mut s.sorted);
    for tile in 0..n2 {
        let entries = &sorted[s.tile_start[tile] as usize..s.tile_start[tile + 1] as usize];
        if entries.is_empty() {
            out.tiles.push(EMPTY_TILE);
            out.stats.empty_tiles += 1;
            continue;
        }
        let offset = out.words.len() as u32;
        let written = out.words.len() as u64;
        let limit = shared.map_or(limit, |pool| limit.min(written + pool.load(Ordering::Relaxed)));
        let block = grid.write_tile(entries, s, &mut out.words, limit)?;
        if let Some(pool) = shared {
            // Another direction may have drawn on the pool since it was read.
            let words = out.words.len() as u64 - written;
            if pool.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| left.checked_sub(words)).is_err() {
                return Err(TooLarge { count: out.words.len() as u64, limit }.into());
            }
        }
        out.tiles.push(offset);
        let depth = (block.leaves as u64).next_power_of_two().trailing_zeros();
        out.stats.tile_triangle_sum += entries.len() as u64;
        out.stats.max_tile_triangles = out.stats.max_tile_triangles.max(entries.len() as u32);
        out.stats.max_depth_used = out.stats.max_depth_used.max(depth);
        out.stats.depth_histogram[depth as usize] += 1;
        out.stats.leaf_count += block.leaves as u64;
        out.stats.id_count += block.refs;
    }
    s.sorted = sorted;
    Ok(out)
}
