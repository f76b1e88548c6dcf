//! The size model of a field: how many bytes each part of a field takes, derived from the sizes
//! of the records of [`crate::layout`] (`size_of`), in one place. The baker's size estimates, its
//! budget checks and the merge's consistency checks all count bytes through these functions.

use crate::layout::*;

/// Bytes of one TILES entry.
pub const TILE: u64 = size_of::<TileEntry>() as u64;
/// Bytes of one LEAVES word.
pub const LEAF_WORD: u64 = size_of::<LeafWord>() as u64;
/// Bytes of one BEAMS record.
pub const BEAM: u64 = size_of::<BeamRecord>() as u64;
/// Bytes of one STATISTICS record (a field holds one).
pub const STATISTICS: u64 = size_of::<StatisticsRecord>() as u64;
/// Bytes each direction adds to DIRECTIONS and ROTATIONS.
pub const DIRECTION_FRAME: u64 = (size_of::<DirectionRecord>() + size_of::<RotationRecord>()) as u64;
/// Bytes each triangle adds to TRIANGLES and PROVENANCE.
pub const TRIANGLE: u64 = (size_of::<TriangleRecord>() + size_of::<ProvenanceRecord>()) as u64;
/// Bytes a ref takes in a tile block: its four box bytes and its triangle id
/// ([`crate::block`]).
pub const REF: u64 = 4 + size_of::<u32>() as u64;
/// What estimates allow for the alignment padding of the small sections: [`SECTION_ALIGN`] bytes
/// before each of sixteen sections.
pub const PADDING_ALLOWANCE: u64 = 16 * SECTION_ALIGN;

/// Bytes of the header and a table of `sections` entries.
pub const fn head(sections: usize) -> u64 {
    (HEADER_SIZE + TABLE_ENTRY_SIZE * sections) as u64
}

/// Bytes one direction adds to the per-direction sections: its BEAMS record, `tiles` TILES
/// entries and `words` LEAVES words.
pub const fn direction(tiles: u64, words: u64) -> u64 {
    BEAM + tiles * TILE + words * LEAF_WORD
}

/// A lower bound on the size of a field of `directions` directions with `tiles_per_direction`
/// tiles each over `triangles` triangles: every tile costs an entry, every triangle lands in at
/// least one leaf of every direction (a ref), every direction has its BEAMS, DIRECTIONS and
/// ROTATIONS records, and every triangle its TRIANGLES and PROVENANCE records.
pub const fn lower_bound(directions: u64, tiles_per_direction: u64, triangles: u64) -> u64 {
    directions * (BEAM + tiles_per_direction * TILE + triangles * REF + DIRECTION_FRAME) + TRIANGLE * triangles
}

/// [`lower_bound`] with `refs` refs in all (the triangle-tile pairs the directions are known to
/// make) in place of one per triangle and direction, when they are more.
pub const fn lower_bound_with_refs(directions: u64, tiles_per_direction: u64, triangles: u64, refs: u64) -> u64 {
    let beyond = refs.saturating_sub(directions.saturating_mul(triangles));
    lower_bound(directions, tiles_per_direction, triangles).saturating_add(beyond.saturating_mul(REF))
}

/// An estimate of a field's size from the mean bytes of its directions (measured on a sample):
/// every direction, the triangles' records, and the [`PADDING_ALLOWANCE`].
pub const fn estimate(directions: u64, bytes_per_direction: u64, triangles: u64) -> u64 {
    directions * bytes_per_direction + TRIANGLE * triangles + PADDING_ALLOWANCE
}

const _: () = {
    // The byte counts of formats/vlf.md §5 that the model above adds up.
    assert!(TILE == 4 && LEAF_WORD == 8 && BEAM == 32 && REF == 8);
    assert!(DIRECTION_FRAME == 16 + 72 && TRIANGLE == 36 + 8 && PADDING_ALLOWANCE == 1024);
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_direction_costs_its_beam_tiles_and_words() {
        assert_eq!(direction(0, 0), 32);
        assert_eq!(direction(4, 10), 32 + 4 * 4 + 10 * 8);
        assert_eq!(head(15), 128 + 15 * 72);
    }

    #[test]
    fn the_lower_bound_counts_one_entry_per_tile_and_one_ref_per_triangle_per_direction() {
        // 3 directions, 16 tiles, 10 triangles.
        let per_direction = 32 + 16 * 4 + 10 * 8 + 16 + 72;
        assert_eq!(lower_bound(3, 16, 10), 3 * per_direction + 10 * 44);
        assert_eq!(estimate(3, 1000, 10), 3000 + 440 + 1024);
        // Refs beyond one per triangle and direction add theirs; fewer change nothing.
        assert_eq!(lower_bound_with_refs(3, 16, 10, 30), lower_bound(3, 16, 10));
        assert_eq!(lower_bound_with_refs(3, 16, 10, 5), lower_bound(3, 16, 10));
        assert_eq!(lower_bound_with_refs(3, 16, 10, 130), lower_bound(3, 16, 10) + 100 * 8);
        assert_eq!(lower_bound_with_refs(3, 16, 10, u64::MAX), u64::MAX);
    }
}
