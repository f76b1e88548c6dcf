//! Section kinds (`formats/vlf.md` §5, `formats/vlf-shard.md` §3): their numbers, names and
//! element sizes, which a version 2 file must hold, which hold per-direction data; and the codecs
//! of the section table (§4, §8).

use crate::layout::*;

/// Section kinds (§5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u32)]
pub enum SectionKind {
    Scene = 1,
    Params = 2,
    Directions = 3,
    Rotations = 4,
    Lookup = 5,
    Beams = 6,
    Tiles = 7,
    Leaves = 8,
    // Kind 9 held TRIANGLE_IDS in format 1; version 2 has no kind 9.
    Triangles = 10,
    Provenance = 11,
    Sources = 12,
    Inputs = 13,
    Strings = 14,
    Statistics = 15,
    Materials = 16,
    Cameras = 17,
    Lights = 18,
    Duplicates = 19,
}

impl SectionKind {
    /// Every kind this crate knows, in the order the writer lays out the small ones.
    pub const ALL: [SectionKind; 18] = [
        SectionKind::Scene,
        SectionKind::Params,
        SectionKind::Directions,
        SectionKind::Rotations,
        SectionKind::Lookup,
        SectionKind::Beams,
        SectionKind::Tiles,
        SectionKind::Leaves,
        SectionKind::Triangles,
        SectionKind::Provenance,
        SectionKind::Sources,
        SectionKind::Inputs,
        SectionKind::Strings,
        SectionKind::Statistics,
        SectionKind::Materials,
        SectionKind::Cameras,
        SectionKind::Lights,
        SectionKind::Duplicates,
    ];

    /// The kinds every version 2 file holds.
    pub const REQUIRED: [SectionKind; 14] = [
        SectionKind::Scene,
        SectionKind::Params,
        SectionKind::Directions,
        SectionKind::Rotations,
        SectionKind::Lookup,
        SectionKind::Beams,
        SectionKind::Tiles,
        SectionKind::Leaves,
        SectionKind::Triangles,
        SectionKind::Provenance,
        SectionKind::Sources,
        SectionKind::Inputs,
        SectionKind::Strings,
        SectionKind::Statistics,
    ];

    /// The optional kinds (added in version 1.1): a file may omit them, which means the same as an
    /// empty section.
    pub const OPTIONAL: [SectionKind; 4] =
        [SectionKind::Materials, SectionKind::Cameras, SectionKind::Lights, SectionKind::Duplicates];

    /// Whether a version 2 file must hold this kind.
    pub const fn is_required(self) -> bool {
        (self as u32) <= SectionKind::Statistics as u32
    }

    pub fn from_u32(kind: u32) -> Option<SectionKind> {
        SectionKind::ALL.iter().copied().find(|k| *k as u32 == kind)
    }

    /// The element size the spec requires.
    pub const fn element_size(self) -> u32 {
        match self {
            SectionKind::Scene => size_of::<SceneRecord>() as u32,
            SectionKind::Params => size_of::<ParamsRecord>() as u32,
            SectionKind::Directions => size_of::<DirectionRecord>() as u32,
            SectionKind::Rotations => size_of::<RotationRecord>() as u32,
            SectionKind::Lookup => size_of::<LookupEntry>() as u32,
            SectionKind::Beams => size_of::<BeamRecord>() as u32,
            SectionKind::Tiles => size_of::<TileEntry>() as u32,
            SectionKind::Leaves => size_of::<LeafWord>() as u32,
            SectionKind::Triangles => size_of::<TriangleRecord>() as u32,
            SectionKind::Provenance => size_of::<ProvenanceRecord>() as u32,
            SectionKind::Sources => size_of::<SourceRecord>() as u32,
            SectionKind::Inputs => size_of::<InputRecord>() as u32,
            SectionKind::Strings => size_of::<u8>() as u32,
            SectionKind::Statistics => size_of::<StatisticsRecord>() as u32,
            SectionKind::Materials => size_of::<MaterialRecord>() as u32,
            SectionKind::Cameras => size_of::<CameraRecord>() as u32,
            SectionKind::Lights => size_of::<LightRecord>() as u32,
            SectionKind::Duplicates => size_of::<DuplicateRecord>() as u32,
        }
    }

    /// The upper-case name used in the spec and in `dump`.
    pub const fn name(self) -> &'static str {
        match self {
            SectionKind::Scene => "SCENE",
            SectionKind::Params => "PARAMS",
            SectionKind::Directions => "DIRECTIONS",
            SectionKind::Rotations => "ROTATIONS",
            SectionKind::Lookup => "LOOKUP",
            SectionKind::Beams => "BEAMS",
            SectionKind::Tiles => "TILES",
            SectionKind::Leaves => "LEAVES",
            SectionKind::Triangles => "TRIANGLES",
            SectionKind::Provenance => "PROVENANCE",
            SectionKind::Sources => "SOURCES",
            SectionKind::Inputs => "INPUTS",
            SectionKind::Strings => "STRINGS",
            SectionKind::Statistics => "STATISTICS",
            SectionKind::Materials => "MATERIALS",
            SectionKind::Cameras => "CAMERAS",
            SectionKind::Lights => "LIGHTS",
            SectionKind::Duplicates => "DUPLICATES",
        }
    }
}

/// Codecs of the section table.
pub mod codec {
    pub const RAW: u32 = 0;
    pub const ZSTD: u32 = 1;
}

/// Display name of a section kind number, known or not.
pub fn kind_name(kind: u32) -> String {
    match SectionKind::from_u32(kind) {
        Some(k) => k.name().to_string(),
        None if kind == SHARD_KIND => "SHARD".to_string(),
        None => format!("unknown kind {kind}"),
    }
}

/// Section kind of the SHARD record (`formats/vlf-shard.md` §3); outside the range of field kinds.
pub const SHARD_KIND: u32 = 0x1_0000;

/// The sections that hold per-direction data. In a shard they hold its directions only (BEAMS
/// bases relative to its first direction, STATISTICS over its directions); every other section of
/// a shard is *shared*: byte for byte the section of the merged field.
pub const PER_DIRECTION_KINDS: [SectionKind; 4] =
    [SectionKind::Beams, SectionKind::Statistics, SectionKind::Tiles, SectionKind::Leaves];

/// Whether sections of `kind` hold per-direction data ([`PER_DIRECTION_KINDS`]).
pub fn is_per_direction(kind: u32) -> bool {
    PER_DIRECTION_KINDS.iter().any(|k| *k as u32 == kind)
}

const _: () = {
    // The element sizes of §5's table.
    assert!(SectionKind::Directions.element_size() == 16);
    assert!(SectionKind::Rotations.element_size() == 72);
    assert!(SectionKind::Lookup.element_size() == 4);
    assert!(SectionKind::Tiles.element_size() == 4);
    assert!(SectionKind::Leaves.element_size() == 8);
    assert!(SectionKind::Triangles.element_size() == 36);
    assert!(SectionKind::Strings.element_size() == 1);
};
