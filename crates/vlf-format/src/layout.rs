//! The on-disk structs, field by field as in `formats/vlf.md`. Every struct is `#[repr(C)]`,
//! `Pod`, free of implicit padding (bytemuck's derive refuses padding), and has its size asserted
//! at compile time, so a cast of file bytes to these types is the spec.

use bytemuck::{Pod, Zeroable};

/// `\x89VLF\r\n\x1a\n`: the PNG trick, catching 7-bit, CR-LF and LF-CR-LF transport damage.
pub const MAGIC: [u8; 8] = [0x89, b'V', b'L', b'F', b'\r', b'\n', 0x1a, b'\n'];
/// The major version this crate reads and writes. A reader refuses any other major.
pub const VERSION_MAJOR: u16 = 1;
/// The minor version this crate writes. Readers of the same major accept any minor. Minor 1 added
/// the optional MATERIALS, CAMERAS and LIGHTS sections.
pub const VERSION_MINOR: u16 = 1;
/// Size of the header in bytes.
pub const HEADER_SIZE: usize = 128;
/// Size of one section-table entry in bytes.
pub const TABLE_ENTRY_SIZE: usize = 72;
/// Sections start at multiples of this.
pub const SECTION_ALIGN: u64 = 64;
/// Upper bound on `section_count`, so a corrupt count cannot make a reader allocate or loop much.
pub const MAX_SECTIONS: u32 = 4096;
/// Byte range of the `content_hash` field inside the header, taken as zero when hashing.
pub const CONTENT_HASH_RANGE: std::ops::Range<usize> = 48..80;
/// The most a zstd frame can expand: every block yields at most 128 KiB and takes at least 4
/// bytes (a 3-byte block header and one byte of content), so `raw_length` of a zstd section is at
/// most this many times its `stored_length` (`formats/vlf.md` §8). Readers refuse a table entry
/// that claims more, before allocating anything for it.
pub const MAX_ZSTD_EXPANSION: u64 = 32768;
/// The largest BSP depth a file may record.
pub const MAX_DEPTH: u32 = 24;
/// Quantisation levels of a tile's z range: `z(q) = -R + q * (2R / Z_LEVELS)`.
pub const Z_LEVELS: u32 = 65535;
/// LOOKUP value of a cell that is not a lattice point.
pub const LOOKUP_NONE: u32 = u32::MAX;
/// LOOKUP flag: the stored direction is the antipode of the lattice point.
pub const LOOKUP_FLIP: u32 = 1 << 31;
/// A node field that does not apply (OBJ sources).
pub const NO_INDEX: u32 = u32::MAX;

/// The file header (§3).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct Header {
    pub magic: [u8; 8],
    pub version_major: u16,
    pub version_minor: u16,
    pub header_size: u32,
    pub file_length: u64,
    pub table_offset: u64,
    pub section_count: u32,
    pub table_entry_size: u32,
    pub flags: u32,
    pub reserved0: u32,
    pub content_hash: [u8; 32],
    pub input_hash: [u8; 32],
    pub reserved1: [u8; 16],
}

/// One entry of the section table (§4).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct SectionEntry {
    pub kind: u32,
    pub codec: u32,
    pub offset: u64,
    pub stored_length: u64,
    pub raw_length: u64,
    pub element_size: u32,
    pub reserved: u32,
    pub raw_hash: [u8; 32],
}

/// The request: parameters as asked for, part of the input hash (§3.3).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
#[repr(C)]
pub struct Request {
    pub requested_directions: u32,
    pub requested_tiles: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub max_bytes: u64,
    pub max_bytes_per_triangle: u64,
}

/// SCENE (§5.1): the bounding sphere that normalises the scene.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct SceneRecord {
    pub center: [f64; 3],
    pub radius: f64,
    pub aabb_min: [f64; 3],
    pub aabb_max: [f64; 3],
    pub triangle_count: u64,
    pub source_count: u32,
    pub input_count: u32,
    pub dropped_degenerate: u64,
    pub reserved: [u64; 3],
}

/// PARAMS (§5.2).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct ParamsRecord {
    pub lattice_n: u32,
    pub direction_count: u32,
    pub tile_resolution: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub requested_directions: u32,
    pub requested_tiles: u32,
    pub reserved0: u32,
    pub max_bytes: u64,
    pub margin: f64,
    pub max_bytes_per_triangle: u64,
    pub reserved1: u64,
}

/// BEAMS (§5.5): where one direction's leaves and ids live.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
#[repr(C)]
pub struct BeamRecord {
    pub leaf_base: u64,
    pub leaf_count: u64,
    pub id_base: u64,
    pub id_count: u64,
}

/// TILES (§5.6): one tile's linearised 1D BSP.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct TileRecord {
    pub first_leaf: u32,
    pub z_lo: u16,
    pub z_hi: u16,
    pub depth: u8,
    pub reserved: [u8; 3],
}

impl TileRecord {
    /// The record of a tile that holds no triangle.
    pub const fn empty(first_leaf: u32) -> Self {
        TileRecord { first_leaf, z_lo: u16::MAX, z_hi: 0, depth: 0, reserved: [0; 3] }
    }

    /// Whether the tile holds no triangle (its z range is empty).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.z_lo >= self.z_hi
    }
}

/// TRIANGLES (§5.7): three world-space vertices, each padded to four floats.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct TriangleRecord {
    pub v: [[f32; 4]; 3],
}

impl TriangleRecord {
    pub fn new(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> Self {
        let p = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
        TriangleRecord { v: [p(v0), p(v1), p(v2)] }
    }

    /// Vertex `i` (0, 1 or 2) without the padding.
    #[inline(always)]
    pub fn vertex(&self, i: usize) -> [f32; 3] {
        [self.v[i][0], self.v[i][1], self.v[i][2]]
    }
}

/// PROVENANCE (§5.8): where triangle `i` came from.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct ProvenanceRecord {
    pub source: u32,
    pub index: u32,
}

/// SOURCES (§5.8).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct SourceRecord {
    pub input: u32,
    pub kind: u32,
    pub name_offset: u32,
    pub name_length: u32,
    pub mesh: u32,
    pub primitive: u32,
    pub node: u32,
    pub material: u32,
}

/// SOURCES `kind` values.
pub mod source_kind {
    pub const OBJ_OBJECT: u32 = 1;
    pub const GLTF_PRIMITIVE: u32 = 2;
    pub const PROGRAM: u32 = 3;
}

/// INPUTS (§5.8).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct InputRecord {
    pub name_offset: u32,
    pub name_length: u32,
    pub triangle_count: u64,
    pub file_hash: [u8; 32],
}

/// MATERIALS (§5.10): one surface of the Whitted model, keyed by (input, index in that input).
/// Colours are linear RGB.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct MaterialRecord {
    pub input: u32,
    pub index: u32,
    pub name_offset: u32,
    pub name_length: u32,
    pub diffuse: [f32; 3],
    pub shininess: f32,
    pub specular: [f32; 3],
    pub ior: f32,
    pub reflection: [f32; 3],
    pub reserved0: u32,
    pub transmission: [f32; 3],
    pub reserved1: u32,
    pub emission: [f32; 3],
    pub reserved2: u32,
}

/// CAMERAS (§5.11): a camera placed by a node, in world space.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct CameraRecord {
    pub kind: u32,
    pub input: u32,
    pub camera: u32,
    pub node: u32,
    pub name_offset: u32,
    pub name_length: u32,
    pub position: [f32; 3],
    pub forward: [f32; 3],
    pub up: [f32; 3],
    pub yfov: f32,
    pub aspect_ratio: f32,
    pub znear: f32,
    pub zfar: f32,
    pub xmag: f32,
    pub ymag: f32,
    pub reserved: u32,
}

/// CAMERAS `kind` values.
pub mod camera_kind {
    pub const PERSPECTIVE: u32 = 1;
    pub const ORTHOGRAPHIC: u32 = 2;
}

/// LIGHTS (§5.12): a punctual light placed by a node, in world space.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct LightRecord {
    pub kind: u32,
    pub input: u32,
    pub light: u32,
    pub node: u32,
    pub name_offset: u32,
    pub name_length: u32,
    pub position: [f32; 3],
    pub direction: [f32; 3],
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: f32,
    pub inner_cone: f32,
    pub outer_cone: f32,
    pub reserved: u32,
}

/// LIGHTS `kind` values.
pub mod light_kind {
    pub const POINT: u32 = 1;
    pub const SPOT: u32 = 2;
    pub const DIRECTIONAL: u32 = 3;
}

/// STATISTICS (§5.9).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct StatisticsRecord {
    pub tile_count: u64,
    pub empty_tiles: u64,
    pub tile_triangle_sum: u64,
    pub max_tile_triangles: u32,
    pub max_depth_used: u32,
    pub leaf_count: u64,
    pub id_count: u64,
    pub depth_histogram: [u64; 32],
    pub reserved: [u64; 10],
}

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
    LeafBounds = 8,
    TriangleIds = 9,
    Triangles = 10,
    Provenance = 11,
    Sources = 12,
    Inputs = 13,
    Strings = 14,
    Statistics = 15,
    Materials = 16,
    Cameras = 17,
    Lights = 18,
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
        SectionKind::LeafBounds,
        SectionKind::TriangleIds,
        SectionKind::Triangles,
        SectionKind::Provenance,
        SectionKind::Sources,
        SectionKind::Inputs,
        SectionKind::Strings,
        SectionKind::Statistics,
        SectionKind::Materials,
        SectionKind::Cameras,
        SectionKind::Lights,
    ];

    /// The kinds every version 1 file holds (the kinds of version 1.0).
    pub const REQUIRED: [SectionKind; 15] = [
        SectionKind::Scene,
        SectionKind::Params,
        SectionKind::Directions,
        SectionKind::Rotations,
        SectionKind::Lookup,
        SectionKind::Beams,
        SectionKind::Tiles,
        SectionKind::LeafBounds,
        SectionKind::TriangleIds,
        SectionKind::Triangles,
        SectionKind::Provenance,
        SectionKind::Sources,
        SectionKind::Inputs,
        SectionKind::Strings,
        SectionKind::Statistics,
    ];

    /// The kinds added in version 1.1: a file may omit them, which means the same as an empty
    /// section (a 1.0 file has none).
    pub const OPTIONAL: [SectionKind; 3] = [SectionKind::Materials, SectionKind::Cameras, SectionKind::Lights];

    /// Whether a version 1 file must hold this kind.
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
            SectionKind::Directions => 16,
            SectionKind::Rotations => 72,
            SectionKind::Lookup => 4,
            SectionKind::Beams => size_of::<BeamRecord>() as u32,
            SectionKind::Tiles => size_of::<TileRecord>() as u32,
            SectionKind::LeafBounds => 4,
            SectionKind::TriangleIds => 4,
            SectionKind::Triangles => size_of::<TriangleRecord>() as u32,
            SectionKind::Provenance => size_of::<ProvenanceRecord>() as u32,
            SectionKind::Sources => size_of::<SourceRecord>() as u32,
            SectionKind::Inputs => size_of::<InputRecord>() as u32,
            SectionKind::Strings => 1,
            SectionKind::Statistics => size_of::<StatisticsRecord>() as u32,
            SectionKind::Materials => size_of::<MaterialRecord>() as u32,
            SectionKind::Cameras => size_of::<CameraRecord>() as u32,
            SectionKind::Lights => size_of::<LightRecord>() as u32,
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
            SectionKind::LeafBounds => "LEAF_BOUNDS",
            SectionKind::TriangleIds => "TRIANGLE_IDS",
            SectionKind::Triangles => "TRIANGLES",
            SectionKind::Provenance => "PROVENANCE",
            SectionKind::Sources => "SOURCES",
            SectionKind::Inputs => "INPUTS",
            SectionKind::Strings => "STRINGS",
            SectionKind::Statistics => "STATISTICS",
            SectionKind::Materials => "MATERIALS",
            SectionKind::Cameras => "CAMERAS",
            SectionKind::Lights => "LIGHTS",
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
        None if kind == crate::shard::SHARD_KIND => "SHARD".to_string(),
        None => format!("unknown kind {kind}"),
    }
}

const _: () = {
    assert!(size_of::<Header>() == HEADER_SIZE);
    assert!(size_of::<SectionEntry>() == TABLE_ENTRY_SIZE);
    assert!(size_of::<Request>() == 32);
    assert!(size_of::<SceneRecord>() == 128);
    assert!(size_of::<ParamsRecord>() == 64);
    assert!(size_of::<BeamRecord>() == 32);
    assert!(size_of::<TileRecord>() == 12);
    assert!(size_of::<TriangleRecord>() == 48);
    assert!(size_of::<ProvenanceRecord>() == 8);
    assert!(size_of::<SourceRecord>() == 32);
    assert!(size_of::<InputRecord>() == 48);
    assert!(size_of::<StatisticsRecord>() == 384);
    assert!(size_of::<MaterialRecord>() == 96);
    assert!(size_of::<CameraRecord>() == 88);
    assert!(size_of::<LightRecord>() == 80);
    assert!(std::mem::offset_of!(MaterialRecord, specular) == 32);
    assert!(std::mem::offset_of!(MaterialRecord, emission) == 80);
    assert!(std::mem::offset_of!(CameraRecord, yfov) == 60);
    assert!(std::mem::offset_of!(LightRecord, intensity) == 60);
    // Field offsets the spec names explicitly.
    assert!(std::mem::offset_of!(Header, content_hash) == 48);
    assert!(std::mem::offset_of!(Header, input_hash) == 80);
    assert!(std::mem::offset_of!(SectionEntry, raw_hash) == 40);
    assert!(std::mem::offset_of!(StatisticsRecord, depth_histogram) == 48);
};
