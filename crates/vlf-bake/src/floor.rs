//! What a bake's directions make at least, known before any of them is baked: their
//! rasterisations' entries, from the triangles' projected areas ([`vlf_raster::Areas`]). Explicit
//! parameters are held to `--max-bytes` by it, and every bake's memory and disk checks count it:
//! on a grid far finer than the triangles, each triangle lands in thousands of tiles, which the
//! per-tile figures alone do not see. A field's floor is measured once, while its parameters are
//! chosen ([`crate::params::Measure::coverage`]), and reaches the checks in the choice
//! ([`EntryFloor::of_field`]); a shard's is measured on its own directions.

use crate::params::Coverage;
use crate::prepare::Prepared;
use rayon::prelude::*;
use std::ops::Range;
use vlf_format::size;
use vlf_geom::Lattice;
use vlf_geom::frame::frame;
use vlf_raster::{Areas, Grid};

/// Directions measured at most, spread evenly over the range; the others count one entry per
/// triangle (still a lower bound).
pub const MAX_MEASURED: u64 = 4096;

/// Triangle-direction pairs measured at most: for a million random triangles, 0.31 s on one core
/// of a Zen 4 EPYC and 0.18 s on two (the area and longest-edge terms, 64 bytes a triangle).
pub const MAX_PAIRS: u64 = 1 << 26;

/// Lower bounds on the entries of a range of a field's directions.
#[derive(Clone, Debug, PartialEq)]
pub struct EntryFloor {
    /// The directions covered.
    pub directions: Range<u32>,
    /// What they make at least.
    pub coverage: Coverage,
}

impl EntryFloor {
    /// One entry per triangle in each direction: the floor where no direction is measured.
    pub fn per_triangle(triangles: u64, directions: Range<u32>) -> EntryFloor {
        let coverage = Coverage::one_each(triangles, directions.len() as u64);
        EntryFloor { directions, coverage }
    }

    /// The floor of all `directions` of a field, from the coverage its parameters were chosen with
    /// ([`Choice::coverage`](crate::params::Choice::coverage), which a prepared scene measures
    /// with [`EntryFloor::measure`]): not measured again.
    pub fn of_field(coverage: Coverage, directions: u32) -> EntryFloor {
        EntryFloor { directions: 0..directions, coverage }
    }

    /// At least how many bytes a field (or shard) of these directions on `tiles`² tiles over
    /// `triangles` triangles takes: [`size::lower_bound_with_refs`], a ref for each entry.
    pub fn bytes_at_least(&self, tiles: u32, triangles: u64) -> u64 {
        let (directions, tiles) = (self.directions.len() as u64, tiles as u64 * tiles as u64);
        size::lower_bound_with_refs(directions, tiles, triangles, self.coverage.at_least)
    }

    /// The floor of `directions` of the field on `grid` over `prep`, measured on as many of them
    /// as [`MAX_MEASURED`] and [`MAX_PAIRS`] allow (in parallel on the current thread pool).
    pub fn measure(prep: &Prepared<'_>, grid: &Grid, directions: Range<u32>) -> EntryFloor {
        let triangles = prep.triangle_count() as u64;
        let count = directions.len() as u64;
        let mut floor = EntryFloor::per_triangle(triangles, directions.clone());
        let measured = count.min(MAX_MEASURED).min(MAX_PAIRS / triangles.max(1));
        if measured == 0 {
            return floor;
        }
        // The picked directions only, each found from its index: a lattice may have 2²⁵ + 1.
        let lattice = Lattice::new(grid.lattice_n);
        let rotations: Vec<[f64; 9]> = (0..measured)
            .map(|i| {
                frame(
                    lattice.direction_at(directions.start as u64 + i * count / measured).expect("a field's direction"),
                )
            })
            .collect();
        let areas = Areas::new(&prep.vertices, &prep.triangles);
        let bounds: Vec<u64> = rotations.par_iter().map(|m| areas.entries_at_least(grid, m)).collect();
        // Each measured direction adds what it makes beyond the one entry per triangle counted.
        let c = &mut floor.coverage;
        c.at_least = c.at_least.saturating_add(bounds.iter().map(|b| b - triangles).sum());
        c.largest = bounds.iter().copied().max().unwrap_or(triangles);
        c.per_direction = bounds.iter().sum::<u64>() as f64 / measured as f64;
        floor
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use vlf_raster::DepthPolicy;
    use vlf_raster::MAX_WORDS;

    /// A grid of `side`² unit squares (two triangles each) in the plane z = x / 2.
    fn sheet(side: usize) -> Scene {
        let mut triangles = Vec::new();
        for i in 0..side {
            for j in 0..side {
                let p = |di: usize, dj: usize| {
                    let (x, y) = ((i + di) as f32, (j + dj) as f32);
                    [x, y, x / 2.0]
                };
                triangles.push([p(0, 0), p(1, 0), p(1, 1)]);
                triangles.push([p(0, 0), p(1, 1), p(0, 1)]);
            }
        }
        Scene::from_triangles("sheet", &triangles).unwrap()
    }

    #[test]
    fn the_floor_is_at_most_what_the_directions_make_and_counts_fine_tiles() {
        let scene = sheet(12);
        let prep = Prepared::new(&scene);
        let grid = Grid { tiles: 64, lattice_n: 3, radius: prep.radius, margin: 1e-6, depth: DepthPolicy::default() };
        let lattice = Lattice::new(3).directions();
        let made: Vec<u64> = lattice
            .iter()
            .map(|&d| {
                // The raster kernel itself (not the bake's wrapper, which imports what imports
                // this module).
                let (v, t, m) = (&prep.vertices, &prep.triangles, frame(d));
                let data =
                    vlf_raster::build_direction(v, t, &grid, &m, &mut vlf_raster::Scratch::default(), MAX_WORDS, None);
                data.unwrap().stats.tile_triangle_sum
            })
            .collect();
        let all = EntryFloor::measure(&prep, &grid, 0..lattice.len() as u32);
        assert!(all.coverage.at_least <= made.iter().sum::<u64>(), "{all:?} against {made:?}");
        assert!(all.coverage.largest <= *made.iter().max().unwrap());
        // The sheet is 12 × 12 × √1.25 ≈ 161 square units across a grid 2R ≈ 19 wide: on 64² tiles
        // each of its 288 triangles covers several of them in most directions.
        let triangles = prep.triangle_count() as u64;
        assert!(all.coverage.at_least > 2 * triangles * lattice.len() as u64, "{all:?}");
        // A shard's floor covers its directions only, and the floors of a partition add up.
        let (a, b) = (EntryFloor::measure(&prep, &grid, 0..7), EntryFloor::measure(&prep, &grid, 7..19));
        assert_eq!(a.coverage.at_least + b.coverage.at_least, all.coverage.at_least);
        assert_eq!(a.coverage.largest.max(b.coverage.largest), all.coverage.largest);
        // Bytes: the format's lower bound, plus a ref for each entry beyond one per triangle.
        let plain = size::lower_bound(19, 64 * 64, triangles);
        assert_eq!(all.bytes_at_least(64, triangles), plain + (all.coverage.at_least - 19 * triangles) * size::REF);
        assert_eq!(EntryFloor::per_triangle(triangles, 0..19).bytes_at_least(64, triangles), plain);
    }
}
