//! The per-direction kernel (paper §3.1, §3.2, §4 and §5): rotate the scene into one direction's
//! canonical frame, rasterise every triangle conservatively into the `n × n` tiles, and give each
//! tile a linearised 1D BSP along the beam (`formats/vlf.md` §5.6, §6).

use crate::error::BakeError;
use crate::params::Params;
use crate::prepare::Prepared;
use crate::raster::rasterize;
use vlf_format::{StatisticsRecord, TileRecord, Z_LEVELS, size};
use vlf_geom::frame::mul;

/// One direction's part of the TILES, LEAF_BOUNDS and TRIANGLE_IDS sections.
pub struct DirectionData {
    pub tiles: Vec<TileRecord>,
    /// `leaf_count + 1` bounds, relative to the direction's first id.
    pub bounds: Vec<u32>,
    pub ids: Vec<u32>,
    pub stats: StatisticsRecord,
}

impl DirectionData {
    /// Bytes this direction adds to the file.
    pub fn bytes(&self) -> u64 {
        size::direction(self.tiles.len() as u64, self.bounds.len() as u64, self.ids.len() as u64)
    }
}

/// One rasterised (tile, triangle) pair with the triangle's z range in the tile, grown by μ.
#[derive(Clone, Copy)]
struct Entry {
    tile: u32,
    tri: u32,
    z0: f64,
    z1: f64,
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub struct Scratch {
    projected: Vec<[f64; 3]>,
    entries: Vec<Entry>,
    sorted: Vec<Entry>,
    tile_start: Vec<u32>,
    leaf_fill: Vec<u32>,
}

/// Builds direction `j` (rotation `m`): its tiles, leaf bounds, ids and statistics.
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

    // Canonical coordinates: (u, v) in tile units, z in world units.
    s.projected.clear();
    s.projected.extend(prep.vertices.iter().map(|&v| {
        let p = mul(m, v);
        [(p[0] + r) / w, (p[1] + r) / w, p[2]]
    }));
    s.entries.clear();
    for (id, tri) in prep.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|k| s.projected[k as usize]);
        let entries = &mut s.entries;
        rasterize(a, b, c, n, e, |ix, iy, z0, z1| {
            entries.push(Entry { tile: iy * n + ix, tri: id as u32, z0: z0 - margin, z1: z1 + margin });
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
    s.sorted.resize(s.entries.len(), Entry { tile: 0, tri: 0, z0: 0.0, z1: 0.0 });
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
        bounds: Vec::with_capacity(n2 + 1),
        ids: Vec::with_capacity(s.entries.len() + s.entries.len() / 2),
        stats: StatisticsRecord::zeroed_record(),
    };
    out.stats.tile_count = n2 as u64;
    let z_step = 2.0 * r / Z_LEVELS as f64;
    let mut first_leaf: u64 = 0;
    for tile in 0..n2 {
        let entries = &s.sorted[s.tile_start[tile] as usize..s.tile_start[tile + 1] as usize];
        if first_leaf > u32::MAX as u64 {
            return Err(BakeError::DirectionTooLarge { direction: j, count: first_leaf, what: "leaves" });
        }
        if entries.is_empty() {
            out.tiles.push(TileRecord::empty(first_leaf as u32));
            out.bounds.push(out.ids.len() as u32);
            out.stats.empty_tiles += 1;
            first_leaf += 1;
            continue;
        }
        let (zmin, zmax) =
            entries.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), en| (a.min(en.z0), b.max(en.z1)));
        // Quantise outward; a non-empty tile has z_lo < z_hi. (Casts truncate toward zero, which
        // equals floor here because negative values clamp to 0 anyway, and avoids a libm call.)
        let q_lo = (((zmin + r) / z_step) as i64).clamp(0, Z_LEVELS as i64 - 1) as u32;
        let above = (zmax + r) / z_step;
        let q_hi =
            (above as i64 + ((above as i64 as f64) < above) as i64).clamp(q_lo as i64 + 1, Z_LEVELS as i64) as u32;
        let z0 = -r + q_lo as f64 * z_step;
        let z1 = -r + q_hi as f64 * z_step;
        let depth = params.depth.depth_for(entries.len() as u64);
        let count = 1usize << depth;
        let h = (z1 - z0) / count as f64;
        // Truncation equals floor under the clamp (see above); the runtime computes the same.
        let leaf_of = |z: f64| (((z - z0) / h) as i64).clamp(0, count as i64 - 1) as usize;

        // Push each triangle to the leaves its (clipped, grown) z range overlaps: count, then fill.
        s.leaf_fill.clear();
        s.leaf_fill.resize(count + 1, 0);
        for en in entries {
            for k in leaf_of(en.z0)..=leaf_of(en.z1) {
                s.leaf_fill[k + 1] += 1;
            }
        }
        for k in 0..count {
            s.leaf_fill[k + 1] += s.leaf_fill[k];
        }
        let base = out.ids.len();
        for k in 0..count {
            out.bounds.push((base + s.leaf_fill[k] as usize) as u32);
        }
        out.ids.resize(base + s.leaf_fill[count] as usize, 0);
        for en in entries {
            for k in leaf_of(en.z0)..=leaf_of(en.z1) {
                out.ids[base + s.leaf_fill[k] as usize] = en.tri;
                s.leaf_fill[k] += 1;
            }
        }
        if out.ids.len() as u64 > u32::MAX as u64 {
            return Err(BakeError::DirectionTooLarge {
                direction: j,
                count: out.ids.len() as u64,
                what: "triangle ids",
            });
        }
        out.tiles.push(TileRecord {
            first_leaf: first_leaf as u32,
            z_lo: q_lo as u16,
            z_hi: q_hi as u16,
            depth: depth as u8,
            reserved: [0; 3],
        });
        first_leaf += count as u64;
        out.stats.tile_triangle_sum += entries.len() as u64;
        out.stats.max_tile_triangles = out.stats.max_tile_triangles.max(entries.len() as u32);
        out.stats.max_depth_used = out.stats.max_depth_used.max(depth);
        out.stats.depth_histogram[depth as usize] += 1;
    }
    if first_leaf > u32::MAX as u64 {
        return Err(BakeError::DirectionTooLarge { direction: j, count: first_leaf, what: "leaves" });
    }
    out.bounds.push(out.ids.len() as u32);
    out.stats.leaf_count = first_leaf;
    out.stats.id_count = out.ids.len() as u64;
    Ok(out)
}
