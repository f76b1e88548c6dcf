//! The on-disk structs, field by field as in `formats/vlf.md` (and `formats/vlf-shard.md` for the
//! SHARD record). Every struct is `#[repr(C)]`, `Pod`, free of implicit padding (bytemuck's derive
//! refuses padding), and has its size asserted at compile time, so a cast of file bytes to these
//! types is the spec. Every field says its unit, encoding and sentinels, and the section of the
//! spec that defines it. Integers and floats are little-endian (§1); lengths and offsets are bytes.

use bytemuck::{Pod, Zeroable};

/// `\x89VLF\r\n\x1a\n`: the PNG trick, catching 7-bit, CR-LF and LF-CR-LF transport damage.
pub const MAGIC: [u8; 8] = [0x89, b'V', b'L', b'F', b'\r', b'\n', 0x1a, b'\n'];
/// `\x89VLS\r\n\x1a\n`: the magic of shard files (`formats/vlf-shard.md`), a field's magic with
/// `F` replaced by `S`, keeping the transfer checks; a field reader refuses it.
pub const SHARD_MAGIC: [u8; 8] = [0x89, b'V', b'L', b'S', b'\r', b'\n', 0x1a, b'\n'];
/// The major version this crate reads and writes. A reader refuses any other major. Major 2
/// replaced the tiles' complete BSPs of fixed-size leaves with tile blocks (§5.6) and stores
/// triangles relative to the scene's centre (§5.7).
pub const VERSION_MAJOR: u16 = 2;
/// The minor version this crate writes. Readers of the same major accept any minor.
pub const VERSION_MINOR: u16 = 0;
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
/// The largest leaf-split depth the leaf policy may ask for (§6.3): a tile has at most
/// `2^MAX_DEPTH` leaves, which is [`crate::block::MAX_LEAVES`].
pub const MAX_DEPTH: u32 = 12;
/// Quantisation levels of the beam coordinate of leaf boundaries: `z(q) = -R + q * (2R / Z_LEVELS)`.
pub const Z_LEVELS: u32 = 65535;
/// LOOKUP value of a cell that is not a lattice point.
pub const LOOKUP_NONE: u32 = u32::MAX;
/// LOOKUP flag: the stored direction is the antipode of the lattice point.
pub const LOOKUP_FLIP: u32 = 1 << 31;
/// A node field that does not apply (OBJ sources).
pub const NO_INDEX: u32 = u32::MAX;

/// DIRECTIONS element (§5.3): the unit direction `(x, y, z, 0)` of a lattice point, computed in
/// f64 and rounded to f32; `z ≥ 0` (upper hemisphere).
pub type DirectionRecord = [f32; 4];

/// ROTATIONS element (§5.4): the row-major 3×3 matrix `M_j` whose rows are `t1, t2, ω_j`, an
/// orthonormal frame with `M_j ω_j = +z`, in f64. Defines the tiling: readers use it as stored.
pub type RotationRecord = [f64; 9];

/// LOOKUP element (§5.3): `j | (f << 31)`, the index `j` of the stored direction on a lattice
/// point's line with [`LOOKUP_FLIP`] `f` set when it is the point's antipode; [`LOOKUP_NONE`] for
/// a cell that is not a lattice point.
pub type LookupEntry = u32;

/// TILES element (§5.6): where the tile's block starts in LEAVES, in 8-byte words from its
/// direction's `leaves_base`; [`EMPTY_TILE`] for a tile that holds no triangle.
pub type TileEntry = u32;

/// The TILES value of a tile that holds no triangle.
pub const EMPTY_TILE: TileEntry = u32::MAX;

/// LEAVES element (§5.6): an 8-byte word of the tile blocks ([`crate::block`]).
pub type LeafWord = u64;

/// The file header (§3), 128 bytes at offset 0.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct Header {
    /// [`MAGIC`] for a field, [`SHARD_MAGIC`] for a shard.
    pub magic: [u8; 8],
    /// [`VERSION_MAJOR`]; a reader refuses a major it does not know (§3).
    pub version_major: u16,
    /// The minor version the writer wrote (§3.4); a reader of the same major accepts any.
    pub version_minor: u16,
    /// [`HEADER_SIZE`], 128.
    pub header_size: u32,
    /// Total length of the file in bytes; the last section's stored bytes end here (§2).
    pub file_length: u64,
    /// Offset of the section table: 128, right after the header.
    pub table_offset: u64,
    /// Number of section-table entries, at most [`MAX_SECTIONS`].
    pub section_count: u32,
    /// [`TABLE_ENTRY_SIZE`], 72.
    pub table_entry_size: u32,
    /// Reserved for flags: 0.
    pub flags: u32,
    /// 0.
    pub reserved0: u32,
    /// BLAKE3 of the header and section table with this field taken as zero (§3.1): commits to
    /// every byte of the file through the sections' `raw_hash`.
    pub content_hash: [u8; 32],
    /// BLAKE3 of the bake's inputs and request (§3.2): equal inputs, equal hash.
    pub input_hash: [u8; 32],
    /// 0.
    pub reserved1: [u8; 16],
}

/// One entry of the section table (§4), 72 bytes; the table starts at offset 128.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct SectionEntry {
    /// Section kind (`crate::SectionKind`, or `crate::SHARD_KIND`); unique within a file.
    /// Readers skip kinds they do not know.
    pub kind: u32,
    /// How the bytes are stored: `crate::codec::RAW` (0) or `crate::codec::ZSTD` (1, one zstd
    /// frame, §8).
    pub codec: u32,
    /// Start of the stored bytes: a multiple of [`SECTION_ALIGN`], entries strictly increasing.
    pub offset: u64,
    /// Length of the stored bytes.
    pub stored_length: u64,
    /// Length after decoding; equals `stored_length` for a raw section, and is at most
    /// [`MAX_ZSTD_EXPANSION`] times it for a zstd one.
    pub raw_length: u64,
    /// Size of one element in bytes (`crate::SectionKind::element_size` for a known kind);
    /// `raw_length` is a multiple of it.
    pub element_size: u32,
    /// 0.
    pub reserved: u32,
    /// BLAKE3 of the raw (decoded) bytes.
    pub raw_hash: [u8; 32],
}

/// The request (§3.3), 32 bytes: the parameters as asked for, before the baker chooses automatic
/// values. Part of the input hash (§3.2); PARAMS repeats it.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
#[repr(C)]
pub struct Request {
    /// Directions asked for (rounded up to a lattice size by the baker); 0 = automatic. Read it
    /// with [`Request::requested_directions`].
    pub requested_directions: u32,
    /// Tiles per side asked for; 0 = automatic. Read it with [`Request::requested_tiles`].
    pub requested_tiles: u32,
    /// Leaf policy: a leaf of at most this many refs is not split, ≥ 1 (§6.3).
    pub leaf_size: u32,
    /// Leaf policy: largest split depth, at most [`MAX_DEPTH`] (§6.3).
    pub max_depth: u32,
    /// Bytes: the size budget of automatic parameters, and a ceiling for explicit ones.
    pub max_bytes: u64,
    /// Bytes per triangle that automatic parameters aim at most at.
    pub max_bytes_per_triangle: u64,
}

/// Decodes "0 means automatic" (§3.3).
fn requested(value: u32) -> Option<u32> {
    (value != 0).then_some(value)
}

impl Request {
    /// The directions asked for, `None` if automatic.
    pub fn requested_directions(&self) -> Option<u32> {
        requested(self.requested_directions)
    }

    /// The tiles per side asked for, `None` if automatic.
    pub fn requested_tiles(&self) -> Option<u32> {
        requested(self.requested_tiles)
    }

    /// Whether the baker chose the parameters: unless both the directions and the tiles were
    /// given, it searches for them under the budget.
    pub fn is_automatic(&self) -> bool {
        self.requested_directions().is_none() || self.requested_tiles().is_none()
    }
}

/// SCENE (§5.1), 128 bytes: the bounding sphere that normalises the scene, and where the scene is:
/// triangles are stored relative to `center` (§5.7).
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct SceneRecord {
    /// Centre `c` of the bounding sphere, world units: the origin of the stored triangles.
    pub center: [f64; 3],
    /// Radius `R > 0` of the bounding sphere, world units; every vertex lies inside it. Tiles
    /// cover `[-R, R]²` around `c`, and the beam coordinate `z` runs over `[-R, R]`.
    pub radius: f64,
    /// Minimum corner of the stored vertices' axis-aligned bounding box, relative to `center`.
    pub aabb_min: [f64; 3],
    /// Maximum corner of that box, relative to `center`.
    pub aabb_max: [f64; 3],
    /// `T`, the triangles stored (elements of TRIANGLES), at most 2³² − 1.
    pub triangle_count: u64,
    /// Elements of SOURCES.
    pub source_count: u32,
    /// Elements of INPUTS.
    pub input_count: u32,
    /// Zero-area triangles the importer dropped (not stored): zero area in the input's own
    /// coordinates (f64).
    pub dropped_degenerate: u64,
    /// Triangles of non-zero area that have zero area once stored as f32 relative to `center`
    /// (dropped: no ray can hit them); a loss of precision, not an input defect.
    pub dropped_precision: u64,
    /// Triangles with the same three stored vertices as an earlier one (in any order), merged
    /// into it: a ray cannot tell them apart.
    pub dropped_duplicates: u64,
    /// 0.
    pub reserved: u64,
}

/// PARAMS (§5.2), 64 bytes: the parameters chosen, and the request they were chosen for.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct ParamsRecord {
    /// `N ≥ 1`, segments per edge of the octahedral lattice (§5.3).
    pub lattice_n: u32,
    /// `l = 2N² + 1`, the directions (elements of DIRECTIONS, ROTATIONS and BEAMS).
    pub direction_count: u32,
    /// `n ≥ 1`, tiles per side of every direction's grid; tile width `w = 2R / n`.
    pub tile_resolution: u32,
    /// Leaf policy: a leaf of at most this many refs is not split (§6.3).
    pub leaf_size: u32,
    /// Leaf policy: largest split depth, at most [`MAX_DEPTH`] (§6.3).
    pub max_depth: u32,
    /// As in the request: 0 = automatic. Read it with [`ParamsRecord::requested_directions`].
    pub requested_directions: u32,
    /// As in the request: 0 = automatic. Read it with [`ParamsRecord::requested_tiles`].
    pub requested_tiles: u32,
    /// 0.
    pub reserved0: u32,
    /// As in the request, bytes.
    pub max_bytes: u64,
    /// `μ > 0`, the conservative dilation of footprints and z ranges in world units (§6.2).
    pub margin: f64,
    /// As in the request, bytes per triangle.
    pub max_bytes_per_triangle: u64,
    /// 0.
    pub reserved1: u64,
}

impl ParamsRecord {
    /// The request the parameters were chosen for (§3.3).
    pub fn request(&self) -> Request {
        Request {
            requested_directions: self.requested_directions,
            requested_tiles: self.requested_tiles,
            leaf_size: self.leaf_size,
            max_depth: self.max_depth,
            max_bytes: self.max_bytes,
            max_bytes_per_triangle: self.max_bytes_per_triangle,
        }
    }

    /// The directions asked for, `None` if automatic.
    pub fn requested_directions(&self) -> Option<u32> {
        requested(self.requested_directions)
    }

    /// The tiles per side asked for, `None` if automatic.
    pub fn requested_tiles(&self) -> Option<u32> {
        requested(self.requested_tiles)
    }

    /// Whether the parameters were chosen automatically ([`Request::is_automatic`]).
    pub fn is_automatic(&self) -> bool {
        self.request().is_automatic()
    }
}

/// BEAMS (§5.5), 32 bytes, one per direction: where the direction's tile blocks live in LEAVES.
/// Directions follow each other without gaps, the first at word 0.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
#[repr(C)]
pub struct BeamRecord {
    /// Index in LEAVES (8-byte words) of the direction's first block.
    pub leaves_base: u64,
    /// Words of LEAVES the direction's blocks take, at most 2³² − 1.
    pub leaves_words: u64,
    /// Leaves of all the direction's tiles (Σ of their blocks' `K`).
    pub leaf_count: u64,
    /// Refs of all the direction's leaves (Σ of their blocks' `m`).
    pub ref_count: u64,
}

/// TRIANGLES (§5.7), 36 bytes: one triangle (its index is its id; in Morton order since baker revision 8), its vertices
/// relative to the scene's centre.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct TriangleRecord {
    /// Its three vertices minus SCENE `center`, rounded to f32 from the importer's f64 world
    /// coordinates (node transforms applied); all finite.
    pub v: [[f32; 3]; 3],
}

impl TriangleRecord {
    pub fn new(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> Self {
        TriangleRecord { v: [v0, v1, v2] }
    }

    /// Vertex `i` (0, 1 or 2), relative to the centre.
    #[inline(always)]
    pub fn vertex(&self, i: usize) -> [f32; 3] {
        self.v[i]
    }
}

/// PROVENANCE (§5.8), 8 bytes: where triangle `i` came from.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct ProvenanceRecord {
    /// Index into SOURCES.
    pub source: u32,
    /// The triangle's index within its source, counting every triangle the source produced,
    /// dropped degenerate ones included.
    pub index: u32,
}

/// SOURCES (§5.8), 32 bytes: an OBJ object or group, or a glTF mesh primitive instanced by a node.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct SourceRecord {
    /// Index into INPUTS.
    pub input: u32,
    /// A [`source_kind`] value.
    pub kind: u32,
    /// Name in STRINGS (byte offset): the OBJ object or group name, the glTF mesh name; may be
    /// empty.
    pub name_offset: u32,
    /// Name length in bytes (UTF-8, not NUL-terminated).
    pub name_length: u32,
    /// OBJ: model index in file order; glTF: mesh index.
    pub mesh: u32,
    /// glTF: primitive index within the mesh; otherwise 0.
    pub primitive: u32,
    /// glTF: node index; otherwise [`NO_INDEX`].
    pub node: u32,
    /// OBJ: material index in the MTL libraries; glTF: material index; [`NO_INDEX`] if none.
    pub material: u32,
}

/// SOURCES `kind` values.
pub mod source_kind {
    /// An OBJ object or group.
    pub const OBJ_OBJECT: u32 = 1;
    /// A glTF mesh primitive instanced by a node.
    pub const GLTF_PRIMITIVE: u32 = 2;
    /// Triangles supplied by a program.
    pub const PROGRAM: u32 = 3;
}

/// INPUTS (§5.8), 48 bytes: one input file.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct InputRecord {
    /// The file's name in STRINGS (byte offset): its final path component only.
    pub name_offset: u32,
    /// Name length in bytes.
    pub name_length: u32,
    /// Triangles stored from this input.
    pub triangle_count: u64,
    /// BLAKE3 of the file's bytes (glTF: the `.gltf` or `.glb` file itself).
    pub file_hash: [u8; 32],
}

/// MATERIALS (§5.10, optional, 1.1), 96 bytes: one surface of the Whitted model, keyed by
/// (input, index in that input), records sorted by that key. Colours are linear RGB (not sRGB),
/// nominally in `[0, 1]`; every value is finite and every colour non-negative.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct MaterialRecord {
    /// Index into INPUTS: the file whose material list this record belongs to.
    pub input: u32,
    /// The material's index in that input: the value a SOURCES `material` holds.
    pub index: u32,
    /// The material's name in STRINGS (byte offset); may be empty.
    pub name_offset: u32,
    /// Name length in bytes.
    pub name_length: u32,
    /// Lambert reflectance.
    pub diffuse: [f32; 3],
    /// Phong exponent, ≥ 0.
    pub shininess: f32,
    /// Colour of Phong highlights.
    pub specular: [f32; 3],
    /// Index of refraction of the material's inside, > 0 (1 = no bending).
    pub ior: f32,
    /// Weight of the mirror-reflected ray.
    pub reflection: [f32; 3],
    /// 0.
    pub reserved0: u32,
    /// Weight of the refracted ray.
    pub transmission: [f32; 3],
    /// 0.
    pub reserved1: u32,
    /// Light the surface emits itself.
    pub emission: [f32; 3],
    /// 0.
    pub reserved2: u32,
}

/// CAMERAS (§5.11, optional, 1.1), 88 bytes: a camera placed by a node, in world space, in the
/// order the importer visits nodes. Angles are radians; distances world units.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct CameraRecord {
    /// A [`camera_kind`] value.
    pub kind: u32,
    /// Index into INPUTS.
    pub input: u32,
    /// glTF camera index.
    pub camera: u32,
    /// glTF node index.
    pub node: u32,
    /// Name in STRINGS (byte offset): the camera's, else the node's, else empty.
    pub name_offset: u32,
    /// Name length in bytes.
    pub name_length: u32,
    /// World-space eye point.
    pub position: [f32; 3],
    /// Unit view direction (the node's −Z axis).
    pub forward: [f32; 3],
    /// Unit up direction (the node's +Y axis, made orthogonal to `forward`).
    pub up: [f32; 3],
    /// Perspective: vertical field of view in `(0, π)`; orthographic: 0.
    pub yfov: f32,
    /// Perspective: width / height, 0 if not given; orthographic: 0.
    pub aspect_ratio: f32,
    /// Near plane distance, ≥ 0.
    pub znear: f32,
    /// Far plane distance; 0 = infinite.
    pub zfar: f32,
    /// Orthographic: half the view's width, > 0; perspective: 0.
    pub xmag: f32,
    /// Orthographic: half the view's height, > 0; perspective: 0.
    pub ymag: f32,
    /// 0.
    pub reserved: u32,
}

/// CAMERAS `kind` values.
pub mod camera_kind {
    /// A pinhole camera (`yfov`, `aspect_ratio`).
    pub const PERSPECTIVE: u32 = 1;
    /// A parallel projection (`xmag`, `ymag`).
    pub const ORTHOGRAPHIC: u32 = 2;
}

/// LIGHTS (§5.12, optional, 1.1), 80 bytes: a `KHR_lights_punctual` light placed by a node, in
/// world space, in node order as for CAMERAS. Angles are radians; distances world units.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct LightRecord {
    /// A [`light_kind`] value.
    pub kind: u32,
    /// Index into INPUTS.
    pub input: u32,
    /// glTF light index.
    pub light: u32,
    /// glTF node index.
    pub node: u32,
    /// Name in STRINGS (byte offset): the light's, else the node's, else empty.
    pub name_offset: u32,
    /// Name length in bytes.
    pub name_length: u32,
    /// World-space position (meaningless for directional lights).
    pub position: [f32; 3],
    /// Unit direction the light travels (the node's −Z axis).
    pub direction: [f32; 3],
    /// Linear RGB, non-negative.
    pub color: [f32; 3],
    /// ≥ 0: candela (lm/sr) for point and spot lights, lux (lm/m²) for directional ones.
    pub intensity: f32,
    /// Distance beyond which the light is cut off; 0 = unlimited.
    pub range: f32,
    /// Spot: angle from `direction` of full intensity; others: 0.
    pub inner_cone: f32,
    /// Spot: angle where intensity reaches 0, `inner_cone < outer_cone ≤ π/2`; others: 0.
    pub outer_cone: f32,
    /// 0.
    pub reserved: u32,
}

/// LIGHTS `kind` values.
pub mod light_kind {
    /// A point light at `position`.
    pub const POINT: u32 = 1;
    /// A spot light at `position` shining along `direction`.
    pub const SPOT: u32 = 2;
    /// A light from infinitely far along `direction`.
    pub const DIRECTIONAL: u32 = 3;
}

/// DUPLICATES (§5.13, optional), 12 bytes: a triangle of the input with the same three stored
/// vertices as a kept triangle, merged into it (a ray cannot tell them apart), with where it came
/// from. Records are sorted by `triangle`, then in import order.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct DuplicateRecord {
    /// The id of the kept triangle it repeats.
    pub triangle: u32,
    /// Its source, an index into SOURCES.
    pub source: u32,
    /// Its index within its source, as in PROVENANCE.
    pub index: u32,
}

/// STATISTICS (§5.9), 384 bytes: facts the baker computed, so that `dump` prints them without
/// reading the tiles; a verifying reader recomputes and compares them. Counts over all directions.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct StatisticsRecord {
    /// Tiles: `l·n²`.
    pub tile_count: u64,
    /// Tiles that hold no triangle.
    pub empty_tiles: u64,
    /// Σ over tiles of the number of distinct triangles in the tile.
    pub tile_triangle_sum: u64,
    /// The most distinct triangles in one tile.
    pub max_tile_triangles: u32,
    /// The largest `⌈log2 K⌉` of any tile's leaf count `K`.
    pub max_depth_used: u32,
    /// Σ `leaf_count_j` of BEAMS.
    pub leaf_count: u64,
    /// Σ `ref_count_j` of BEAMS: refs, a triangle counted once per leaf it is in.
    pub id_count: u64,
    /// `depth_histogram[D]`: non-empty tiles with `⌈log2 K⌉ = D` (`K` leaves).
    pub depth_histogram: [u64; 32],
    /// 0.
    pub reserved: [u64; 10],
}

/// The SHARD record (`formats/vlf-shard.md` §3), 64 bytes: the first section of a shard file (kind
/// `crate::SHARD_KIND`), saying which directions it holds and of which bake.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
#[repr(C)]
pub struct ShardRecord {
    /// `K`, in `0..shard_count`.
    pub shard_index: u32,
    /// `N`, in `1..=65536`.
    pub shard_count: u32,
    /// `l`, the directions of the whole field; equals PARAMS `direction_count`.
    pub direction_count: u32,
    /// `⌊K·l/N⌋`, the shard's first direction.
    pub first_direction: u32,
    /// `⌊(K+1)·l/N⌋`, the end of its directions (exclusive).
    pub end_direction: u32,
    /// The baker revision that wrote the shard (also hashed into the input hash, §3.2).
    pub baker_revision: u32,
    /// Sections of the merged field: the shard's `section_count − 1`.
    pub field_section_count: u32,
    /// 0.
    pub reserved: u32,
    /// `crate::shard::shared_hash` of the shard's shared sections, which every shard of one bake
    /// agrees on.
    pub shared_hash: [u8; 32],
}

const _: () = {
    assert!(size_of::<Header>() == HEADER_SIZE);
    assert!(size_of::<SectionEntry>() == TABLE_ENTRY_SIZE);
    assert!(size_of::<Request>() == 32);
    assert!(size_of::<SceneRecord>() == 128);
    assert!(size_of::<ParamsRecord>() == 64);
    assert!(size_of::<BeamRecord>() == 32);
    assert!(size_of::<TileEntry>() == 4);
    assert!(size_of::<LeafWord>() == 8);
    assert!(size_of::<TriangleRecord>() == 36);
    assert!(size_of::<ProvenanceRecord>() == 8);
    assert!(size_of::<SourceRecord>() == 32);
    assert!(size_of::<InputRecord>() == 48);
    assert!(size_of::<StatisticsRecord>() == 384);
    assert!(size_of::<MaterialRecord>() == 96);
    assert!(size_of::<CameraRecord>() == 88);
    assert!(size_of::<LightRecord>() == 80);
    assert!(size_of::<DuplicateRecord>() == 12);
    assert!(size_of::<ShardRecord>() == 64);
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
