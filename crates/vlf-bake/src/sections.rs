//! The sections every file of a bake shares (`formats/vlf-shard.md`): the scene's and the
//! parameters' sections, and the input hash that identifies the bake (`formats/vlf.md` §3.2).
//!
//! **What the input hash covers** ([`input_hash`]): the format's major version, [`BAKER_REVISION`],
//! the request, the scene's centre, and the raw bytes of TRIANGLES, PROVENANCE, SOURCES, INPUTS,
//! STRINGS, MATERIALS, CAMERAS, LIGHTS and DUPLICATES. Changing what it covers, or the baker's output for the same inputs, is a
//! baker revision bump (and, for the covered list, a format change in `formats/vlf.md`).

use crate::params::Params;
use crate::prepare::Prepared;
use crate::scene::Scene;
use std::borrow::Cow;
use vlf_format::{
    DirectionRecord, ParamsRecord, Request, RotationRecord, SceneRecord, SectionEntry, SectionKind, VERSION_MAJOR,
};
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

/// Bumped whenever the baker's output for the same inputs and request changes (part of the input
/// hash, `formats/vlf.md` §3.2). Revision 2 (format 1.1) adds the MATERIALS, CAMERAS and LIGHTS
/// sections, and with them what an OBJ's `.mtl` files hold, to the input hash. Revision 3 (format
/// 2.0) bakes tile blocks with leaves placed by the surface-area heuristic and boxed refs, stores
/// triangles relative to the scene's centre and hashes that centre. Revision 4 weighs each ref
/// in the heuristic by its box's share of the tile (`formats/vlf.md` §6.3). Revision 5 extends the
/// automatic parameters' ladder to 51 and 73 directions (`crate::params::LADDER`): a bake that
/// asks for automatic parameters may now get a different field for the same request. Revision 6
/// raises the leaf heuristic's cost of visiting a leaf from 1.5 to 2.5 triangle tests
/// (`formats/vlf.md` §6.3): fewer, longer leaves. Revision 7 refines the automatic parameters'
/// tiles to 128² only above 750 triangles per non-empty 64² tile, not 400
/// (`crate::params::DENSE_TILE_LOAD`). Revision 8 stores the triangles in Morton order of their
/// centroids (`crate::order`, `formats/vlf.md` §5.7), so their ids change. Revision 9 raises the
/// smallest budget of automatic parameters from 4 to 16 MiB (`crate::params::MIN_AUTOMATIC_BUDGET`):
/// scenes of up to about 16,000 triangles may get more directions. Revision 10 raises the cost of
/// visiting a leaf to 4 on grids of 128² tiles and finer in fields of 33 directions or more
/// (`vlf_raster::leaves::leaf_cost`, `formats/vlf.md` §6.3): their fields are smaller, and
/// automatic parameters may reach more directions with them. Revision 11 gives automatic
/// parameters at least 2.5 KiB for each of a mesh's first 100,000 triangles
/// (`crate::params::automatic_floor`) and extends their ladder to 99 and 129 directions: scenes
/// of about 6,500 to 250,000 triangles may get larger fields. Revision 12 lets that floor grow past
/// 100,000 triangles as the square root of the triangle count instead of staying at 256 MB: scenes
/// of 100,000 to 625,000 triangles may get larger fields. Revision 13 coarsens the automatic
/// parameters' 64² tiles to 32² where they hold fewer than 64 triangles on average
/// (`crate::params::COARSE_TILE_LOAD`) and climbs the directions again: sparse and small scenes
/// get different fields.
pub const BAKER_REVISION: u32 = 13;

/// The input hash of `formats/vlf.md` §3.2.
pub fn input_hash(scene: &Scene, request: &Request) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"VLF-INPUT\0");
    h.update(&VERSION_MAJOR.to_le_bytes());
    h.update(&BAKER_REVISION.to_le_bytes());
    h.update(bytemuck::bytes_of(request));
    // TRIANGLES are relative to the centre: the centre says where they are.
    h.update(bytemuck::bytes_of(&scene.center));
    for (_, bytes) in input_sections(scene) {
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    *h.finalize().as_bytes()
}

/// Raw bytes of TRIANGLES, PROVENANCE, SOURCES, INPUTS, STRINGS, MATERIALS, CAMERAS, LIGHTS and
/// DUPLICATES, in that order: what the input hash covers (the last four are empty when the inputs
/// define none).
fn input_sections(scene: &Scene) -> [(SectionKind, &[u8]); 9] {
    [
        (SectionKind::Triangles, bytemuck::cast_slice(&scene.triangles)),
        (SectionKind::Provenance, bytemuck::cast_slice(&scene.provenance)),
        (SectionKind::Sources, bytemuck::cast_slice(&scene.sources)),
        (SectionKind::Inputs, bytemuck::cast_slice(&scene.inputs)),
        (SectionKind::Strings, &scene.strings),
        (SectionKind::Materials, bytemuck::cast_slice(&scene.materials)),
        (SectionKind::Cameras, bytemuck::cast_slice(&scene.cameras)),
        (SectionKind::Lights, bytemuck::cast_slice(&scene.lights)),
        (SectionKind::Duplicates, bytemuck::cast_slice(&scene.duplicates)),
    ]
}

/// A section that every file of a bake holds whole: a field, and each of its shards
/// (`formats/vlf-shard.md`), byte for byte.
pub struct SharedSection<'a> {
    pub kind: u32,
    pub element_size: u32,
    pub bytes: Cow<'a, [u8]>,
}

impl<'a> SharedSection<'a> {
    fn new(kind: SectionKind, bytes: impl Into<Cow<'a, [u8]>>) -> Self {
        SharedSection { kind: kind as u32, element_size: kind.element_size(), bytes: bytes.into() }
    }

    /// The table entry this section gets, but for its offset.
    pub fn entry(&self) -> SectionEntry {
        let len = self.bytes.len() as u64;
        SectionEntry {
            kind: self.kind,
            codec: vlf_format::codec::RAW,
            offset: 0,
            stored_length: len,
            raw_length: len,
            element_size: self.element_size,
            reserved: 0,
            raw_hash: *blake3::hash(&self.bytes).as_bytes(),
        }
    }
}

/// The kinds of the shared sections computed from the chosen parameters (with the scene's
/// sphere). Every other shared section depends on the scene alone, which is what the bake cache
/// keys on (`crate::cache`).
pub const PARAMETER_KINDS: [SectionKind; 4] =
    [SectionKind::Params, SectionKind::Directions, SectionKind::Rotations, SectionKind::Lookup];

/// The shared sections that depend on the scene alone, in file order: SCENE, then TRIANGLES,
/// PROVENANCE, SOURCES, INPUTS, STRINGS and the optional MATERIALS, CAMERAS, LIGHTS, DUPLICATES when the
/// inputs define any. A new section derived from the inputs goes here, so that
/// fields, shards, merges and the cache key all carry it.
pub fn scene_sections<'a>(prep: &Prepared<'a>) -> Vec<SharedSection<'a>> {
    let scene = prep.scene;
    let record = SceneRecord {
        center: prep.center,
        radius: prep.radius,
        aabb_min: prep.aabb.0,
        aabb_max: prep.aabb.1,
        triangle_count: scene.triangles.len() as u64,
        source_count: scene.sources.len() as u32,
        input_count: scene.inputs.len() as u32,
        dropped_degenerate: scene.report.dropped_degenerate,
        dropped_precision: scene.report.dropped_precision,
        dropped_duplicates: scene.report.dropped_duplicates,
        reserved: 0,
    };
    // The optional sections (MATERIALS, CAMERAS, LIGHTS) are written only when not empty.
    std::iter::once(SharedSection::new(SectionKind::Scene, bytemuck::bytes_of(&record).to_vec()))
        .chain(
            input_sections(scene)
                .into_iter()
                .filter(|(kind, bytes)| kind.is_required() || !bytes.is_empty())
                .map(|(kind, bytes)| SharedSection::new(kind, bytes)),
        )
        .collect()
}

/// The shared sections computed from the chosen parameters ([`PARAMETER_KINDS`]), in file order.
/// DIRECTIONS and ROTATIONS are written straight into their bytes, direction by direction: a
/// field may have 2²⁵ + 1 directions, and the sections are what a bake holds of them.
fn parameter_sections(params: &Params, request: &Request) -> Vec<SharedSection<'static>> {
    let lattice = Lattice::new(params.lattice_n);
    let l = lattice.direction_count() as usize;
    let mut directions = Vec::with_capacity(l * size_of::<DirectionRecord>());
    let mut rotations = Vec::with_capacity(l * size_of::<RotationRecord>());
    for (a, b) in lattice.point_iter() {
        let d = lattice.direction(a, b);
        let record: DirectionRecord = [d[0] as f32, d[1] as f32, d[2] as f32, 0.0];
        directions.extend_from_slice(bytemuck::bytes_of(&record));
        rotations.extend_from_slice(bytemuck::bytes_of::<RotationRecord>(&frame(d)));
    }
    let record = params_record(params, request);
    vec![
        SharedSection::new(SectionKind::Params, bytemuck::bytes_of(&record).to_vec()),
        SharedSection::new(SectionKind::Directions, directions),
        SharedSection::new(SectionKind::Rotations, rotations),
        SharedSection::new(SectionKind::Lookup, bytemuck::cast_slice(&lattice.lookup_table()).to_vec()),
    ]
}

/// The bytes of memory the parameter sections of a field on lattice `lattice_n` take while a bake
/// holds them, at most: DIRECTIONS and ROTATIONS ([`vlf_format::size::DIRECTION_FRAME`] a
/// direction), and LOOKUP twice (the table, then its bytes, while they are built).
pub fn parameter_bytes(lattice_n: u32) -> u64 {
    let side = 2 * lattice_n as u64 + 1;
    Lattice::new(lattice_n).direction_count() * vlf_format::size::DIRECTION_FRAME + 2 * 4 * side * side
}

/// The PARAMS record (`formats/vlf.md` §5.2) of a bake with `params` chosen for `request`.
pub fn params_record(params: &Params, request: &Request) -> ParamsRecord {
    ParamsRecord {
        lattice_n: params.lattice_n,
        direction_count: Lattice::new(params.lattice_n).direction_count() as u32,
        tile_resolution: params.tiles,
        leaf_size: params.depth.leaf_size,
        max_depth: params.depth.max_depth,
        requested_directions: request.requested_directions,
        requested_tiles: request.requested_tiles,
        reserved0: 0,
        max_bytes: request.max_bytes,
        margin: params.margin,
        max_bytes_per_triangle: request.max_bytes_per_triangle,
        reserved1: 0,
    }
}

/// Every shared section of the field, in file order: SCENE, the parameter sections, then the
/// rest of the scene sections. The per-direction sections (`vlf_format::shard::PER_DIRECTION_KINDS`)
/// follow them in every file a bake writes.
pub fn shared_sections<'a>(prep: &Prepared<'a>, params: &Params, request: &Request) -> Vec<SharedSection<'a>> {
    let mut sections = scene_sections(prep);
    sections.splice(1..1, parameter_sections(params, request));
    sections
}
