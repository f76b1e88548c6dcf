//! The size model of a field: how many bytes each part of a field takes, derived from the sizes
//! of the records of [`crate::layout`] (`size_of`), in one place. The baker's size estimates, its
//! budget checks and the merge's consistency checks all count bytes through these functions.

use crate::layout::*;

/// Bytes of one TILES record.
pub const TILE: u64 = size_of::<TileRecord>() as u64;
/// Bytes of one LEAF_BOUNDS entry.
pub const LEAF_BOUND: u64 = size_of::<LeafBound>() as u64;
/// Bytes of one TRIANGLE_IDS entry.
pub const TRIANGLE_ID: u64 = size_of::<TriangleId>() as u64;
/// Bytes of one BEAMS record.
pub const BEAM: u64 = size_of::<BeamRecord>() as u64;
/// Bytes of one STATISTICS record (a field holds one).
pub const STATISTICS: u64 = size_of::<StatisticsRecord>() as u64;
/// Bytes each direction adds to DIRECTIONS and ROTATIONS.
pub const DIRECTION_FRAME: u64 = (size_of::<DirectionRecord>() + size_of::<RotationRecord>()) as u64;
/// Bytes each triangle adds to TRIANGLES and PROVENANCE.
pub const TRIANGLE: u64 = (size_of::<TriangleRecord>() + size_of::<ProvenanceRecord>()) as u64;
/// What estimates allow for the alignment padding of the small sections: [`SECTION_ALIGN`] bytes
/// before each of sixteen sections.
pub const PADDING_ALLOWANCE: u64 = 16 * SECTION_ALIGN;

/// Bytes of the header and a table of `sections` entries.
pub const fn head(sections: usize) -> u64 {
    (HEADER_SIZE + TABLE_ENTRY_SIZE * sections) as u64
}

/// Bytes one direction adds to the per-direction sections: its BEAMS record, `tiles` TILES
/// records, `bounds` LEAF_BOUNDS entries (its leaves plus one) and `ids` TRIANGLE_IDS entries.
pub const fn direction(tiles: u64, bounds: u64, ids: u64) -> u64 {
    BEAM + tiles * TILE + bounds * LEAF_BOUND + ids * TRIANGLE_ID
}

/// Bytes of LEAF_BOUNDS and TRIANGLE_IDS holding `bounds` and `ids` entries.
pub const fn leaves_and_ids(bounds: u64, ids: u64) -> u64 {
    bounds * LEAF_BOUND + ids * TRIANGLE_ID
}

/// A lower bound on the size of a field of `directions` directions with `tiles_per_direction`
/// tiles each over `triangles` triangles: every tile costs a record and at least one leaf bound,
/// every triangle lands in at least one tile of every direction, every direction has its BEAMS,
/// DIRECTIONS and ROTATIONS records, and every triangle its TRIANGLES and PROVENANCE records.
pub const fn lower_bound(directions: u64, tiles_per_direction: u64, triangles: u64) -> u64 {
    directions * (direction(tiles_per_direction, tiles_per_direction, triangles) + DIRECTION_FRAME)
        + TRIANGLE * triangles
}

/// An estimate of a field's size from the mean bytes of its directions (measured on a sample):
/// every direction, the triangles' records, and the [`PADDING_ALLOWANCE`].
pub const fn estimate(directions: u64, bytes_per_direction: u64, triangles: u64) -> u64 {
    directions * bytes_per_direction + TRIANGLE * triangles + PADDING_ALLOWANCE
}

const _: () = {
    // The byte counts of formats/vlf.md §5 that the model above adds up.
    assert!(TILE == 12 && LEAF_BOUND == 4 && TRIANGLE_ID == 4 && BEAM == 32);
    assert!(DIRECTION_FRAME == 16 + 72 && TRIANGLE == 48 + 8 && PADDING_ALLOWANCE == 1024);
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_direction_costs_its_beam_tiles_bounds_and_ids() {
        assert_eq!(direction(0, 1, 0), 32 + 4);
        assert_eq!(direction(4, 5, 10), 32 + 4 * 12 + 5 * 4 + 10 * 4);
        assert_eq!(leaves_and_ids(3, 7), 40);
        assert_eq!(head(15), 128 + 15 * 72);
    }

    #[test]
    fn the_lower_bound_counts_one_bound_per_tile_and_one_id_per_triangle_per_direction() {
        // 3 directions, 16 tiles, 10 triangles.
        let per_direction = 16 * 12 + 16 * 4 + 10 * 4 + 32 + 16 + 72;
        assert_eq!(lower_bound(3, 16, 10), 3 * per_direction + 10 * 56);
        assert_eq!(estimate(3, 1000, 10), 3000 + 560 + 1024);
    }
}
