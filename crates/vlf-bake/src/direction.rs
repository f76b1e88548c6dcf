//! The per-direction kernel (paper §3.1, §3.2, §4 and §5): rotate the scene into one direction's
//! canonical frame, rasterise every triangle conservatively into the `n × n` tiles with the box of
//! its part in each, cut each tile's z range into leaves ([`crate::leaves`]) and write the tile's
//! block (`formats/vlf.md` §5.6).

use crate::error::BakeError;
use crate::leaves::boundaries;
use crate::params::Params;
use crate::prepare::Prepared;
use crate::raster::{Part, rasterize};
use vlf_format::block::{BOX_CELLS, MAX_LEAVES, Ref, block_words, write_block};
use vlf_format::{EMPTY_TILE, StatisticsRecord, Z_LEVELS, size};
use vlf_geom::frame::mul;

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

/// One rasterised (tile, triangle) pair: the triangle's z range in the tile in quantized levels
/// and its box in box cells, both grown by μ and rounded outward.
#[derive(Clone, Copy, Default)]
struct Entry {
    tile: u32,
    tri: u32,
    z: [u16; 2],
    cells: [u8; 4],
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub struct Scratch {
    projected: Vec<[f64; 3]>,
    entries: Vec<Entry>,
    sorted: Vec<Entry>,
    tile_start: Vec<u32>,
    ranges: Vec<(u32, u32)>,
    bounds: Vec<u32>,
    leaf_refs: Vec<Vec<Ref>>,
}

/// Builds direction `j` (rotation `m`): its TILES entries, its blocks and statistics.
pub fn build_direction(
    prep: &Prepared<'_>,
    params: &Params,
    m: &[f64; 9],
    j: usize,
    s: &mut Scratch,
) -> Result<DirectionData, BakeError> {
    let n = params.tiles;
    let n2 = n as usize * n as usize;
    let r = prep.radius;
    let w = 2.0 * r / n as f64;
    let margin = params.margin;
    let e = margin / w;
    let z_step = 2.0 * r / Z_LEVELS as f64;

    // Canonical coordinates: (u, v) in tile units, z in world units.
    s.projected.clear();
    s.projected.extend(prep.vertices.iter().map(|&v| {
        let p = mul(m, v);
        [(p[0] + r) / w, (p[1] + r) / w, p[2]]
    }));
    // Quantisation, rounding outward. (Casts truncate toward zero, which equals floor here because
    // negative values clamp to 0 anyway, and avoid a libm call.)
    let level_below = |z: f64| (((z + r) / z_step) as i64).clamp(0, Z_LEVELS as i64) as u16;
    let level_above = |z: f64| {
        let x = (z + r) / z_step;
        (x as i64 + ((x as i64 as f64) < x) as i64).clamp(0, Z_LEVELS as i64) as u16
    };
    let cell = |u: f64, tile: u32| (((u - tile as f64) * BOX_CELLS as f64) as i64).clamp(0, BOX_CELLS as i64 - 1) as u8;
    s.entries.clear();
    for (id, tri) in prep.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|k| s.projected[k as usize]);
        let entries = &mut s.entries;
        rasterize(a, b, c, n, e, |ix, iy, p: Part| {
            entries.push(Entry {
                tile: iy * n + ix,
                tri: id as u32,
                z: [level_below(p.z.0 - margin), level_above(p.z.1 + margin)],
                cells: [cell(p.u.0 - e, ix), cell(p.u.1 + e, ix), cell(p.v.0 - e, iy), cell(p.v.1 + e, iy)],
            });
        });
    }

    // Counting sort by tile; stable, so each tile's entries stay in triangle-id order.
    s.tile_start.clear();
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
        let mut cursor = s.tile_start.clone();
        for en in &s.entries {
            let slot = &mut cursor[en.tile as usize];
            s.sorted[*slot as usize] = *en;
            *slot += 1;
        }
    }

    let mut out = DirectionData {
        tiles: Vec::with_capacity(n2),
        words: Vec::with_capacity(s.entries.len() + n2),
        stats: StatisticsRecord::zeroed_record(),
    };
    out.stats.tile_count = n2 as u64;
    for tile in 0..n2 {
        let entries = &s.sorted[s.tile_start[tile] as usize..s.tile_start[tile + 1] as usize];
        if entries.is_empty() {
            out.tiles.push(EMPTY_TILE);
            out.stats.empty_tiles += 1;
            continue;
        }
        // The tile's z range, non-empty.
        s.ranges.clear();
        s.ranges.extend(entries.iter().map(|en| (en.z[0] as u32, en.z[1] as u32)));
        let lo = s.ranges.iter().map(|r| r.0).min().expect("a ref");
        let hi = s.ranges.iter().map(|r| r.1).max().expect("a ref");
        let (lo, hi) = if lo < hi {
            (lo, hi)
        } else if hi < Z_LEVELS {
            (lo, hi + 1)
        } else {
            (lo - 1, hi)
        };
        boundaries(&s.ranges, lo, hi, &params.depth, &mut s.bounds);
        let k = s.bounds.len() - 1;
        debug_assert!(k as u32 <= MAX_LEAVES);
        // Each ref goes to every leaf its closed range meets; entries are in id order, so each
        // leaf's refs are too.
        s.leaf_refs.resize_with(k.max(s.leaf_refs.len()), Vec::new);
        for leaf in &mut s.leaf_refs[..k] {
            leaf.clear();
        }
        for en in entries {
            let (z0, z1) = (en.z[0] as u32, en.z[1] as u32);
            let first = s.bounds[1..k].partition_point(|&b| b < z0);
            for (leaf, refs) in s.leaf_refs[first..k].iter_mut().enumerate() {
                if s.bounds[first + leaf] > z1 {
                    break;
                }
                refs.push(Ref { id: en.tri, x: [en.cells[0], en.cells[1]], y: [en.cells[2], en.cells[3]] });
            }
        }
        let refs: u64 = s.leaf_refs[..k].iter().map(|l| l.len() as u64).sum();
        let offset = out.words.len() as u64;
        if offset + block_words(k, refs as usize) as u64 > u32::MAX as u64 {
            return Err(BakeError::DirectionTooLarge { direction: j, count: offset, what: "words of tile blocks" });
        }
        out.tiles.push(offset as u32);
        let bounds: Vec<u16> = s.bounds.iter().map(|&b| b as u16).collect();
        let leaves: Vec<&[Ref]> = s.leaf_refs[..k].iter().map(|l| l.as_slice()).collect();
        write_block(&bounds, &leaves, &mut out.words);
        let depth = (k as u64).next_power_of_two().trailing_zeros();
        out.stats.tile_triangle_sum += entries.len() as u64;
        out.stats.max_tile_triangles = out.stats.max_tile_triangles.max(entries.len() as u32);
        out.stats.max_depth_used = out.stats.max_depth_used.max(depth);
        out.stats.depth_histogram[depth as usize] += 1;
        out.stats.leaf_count += k as u64;
        out.stats.id_count += refs;
    }
    Ok(out)
}
