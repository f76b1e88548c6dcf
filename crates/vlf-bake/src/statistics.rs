//! The STATISTICS record (`formats/vlf.md` §5.9): summed direction by direction, and digested
//! for people ([`Statistics`]: what `bake`, `dump` and the report print).

use vlf_format::StatisticsRecord;

/// Adds one direction's statistics into the field's.
pub(crate) fn merge_stats(total: &mut StatisticsRecord, d: &StatisticsRecord) {
    total.tile_count += d.tile_count;
    total.empty_tiles += d.empty_tiles;
    total.tile_triangle_sum += d.tile_triangle_sum;
    total.max_tile_triangles = total.max_tile_triangles.max(d.max_tile_triangles);
    total.max_depth_used = total.max_depth_used.max(d.max_depth_used);
    total.leaf_count += d.leaf_count;
    total.id_count += d.id_count;
    for (a, b) in total.depth_histogram.iter_mut().zip(&d.depth_histogram) {
        *a += b;
    }
}

/// Human-facing digest of STATISTICS.
#[derive(Clone, Debug, serde::Serialize, PartialEq)]
pub struct Statistics {
    pub tiles: u64,
    pub empty_tile_share: f64,
    pub mean_triangles_per_tile: f64,
    pub mean_triangles_per_nonempty_tile: f64,
    pub max_triangles_per_tile: u32,
    pub max_depth_used: u32,
    pub mean_depth_nonempty: f64,
    pub depth_histogram: Vec<u64>,
    pub triangle_ids: u64,
    pub leaves: u64,
}

impl Statistics {
    /// Digests a record as stored; saturating, because an unverified file may hold anything.
    pub fn from_record(s: &StatisticsRecord) -> Self {
        let nonempty = s.tile_count.saturating_sub(s.empty_tiles);
        let used = (s.max_depth_used as usize).saturating_add(1).min(32);
        let depth_sum = s
            .depth_histogram
            .iter()
            .enumerate()
            .fold(0u64, |acc, (d, c)| acc.saturating_add((d as u64).saturating_mul(*c)));
        let ratio = |a: u64, b: u64| if b == 0 { 0.0 } else { a as f64 / b as f64 };
        Statistics {
            tiles: s.tile_count,
            empty_tile_share: ratio(s.empty_tiles, s.tile_count),
            mean_triangles_per_tile: ratio(s.tile_triangle_sum, s.tile_count),
            mean_triangles_per_nonempty_tile: ratio(s.tile_triangle_sum, nonempty),
            max_triangles_per_tile: s.max_tile_triangles,
            max_depth_used: s.max_depth_used,
            mean_depth_nonempty: ratio(depth_sum, nonempty),
            depth_histogram: s.depth_histogram[..used].to_vec(),
            triangle_ids: s.id_count,
            leaves: s.leaf_count,
        }
    }
}
