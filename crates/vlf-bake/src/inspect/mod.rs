//! What `vlf-bake dump` shows: a description of a field read from its header, table and small
//! sections only (instant on any size), and the full verification behind `--verify`; [`text`]
//! writes a description out as `dump` prints it.

pub mod text;

use crate::statistics::Statistics;
use serde::Serialize;
use vlf_format::pack::PackedLayout;
use vlf_format::{FieldReader, FormatError, SectionKind, codec, hex, kind_name};
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

#[derive(Debug, Serialize)]
pub struct SectionInfo {
    pub kind: u32,
    pub name: String,
    pub codec: &'static str,
    pub offset: u64,
    pub stored_length: u64,
    pub raw_length: u64,
    pub element_size: u32,
    pub elements: u64,
    pub raw_hash: String,
}

#[derive(Debug, Serialize)]
pub struct InputInfo {
    pub name: String,
    pub triangles: u64,
    pub file_hash: String,
}

/// Everything `dump` prints (and its `--json` keys).
#[derive(Debug, Serialize)]
pub struct Description {
    pub format_version: String,
    pub content_hash: String,
    pub input_hash: String,
    pub file_bytes: u64,
    pub triangle_count: u64,
    pub dropped_degenerate: u64,
    pub direction_count: u32,
    pub lattice_n: u32,
    pub tile_resolution: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub requested_directions: Option<u32>,
    pub requested_tiles: Option<u32>,
    pub max_bytes: u64,
    pub max_bytes_per_triangle: u64,
    pub margin: f64,
    pub center: [f64; 3],
    pub radius: f64,
    pub aabb_min: [f64; 3],
    pub aabb_max: [f64; 3],
    pub worst_direction_angle_deg: f64,
    pub statistics: Statistics,
    pub inputs: Vec<InputInfo>,
    pub sources: usize,
    /// Records in MATERIALS, CAMERAS and LIGHTS (format 1.1; 0 when absent).
    pub materials: usize,
    pub cameras: usize,
    pub lights: usize,
    /// The sections as stored in the file (for a packed field: codecs and stored lengths).
    pub sections: Vec<SectionInfo>,
    /// For a packed field (`formats/vlf.md` §8): what it unpacks to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub packed: Option<PackedInfo>,
}

/// What a packed field unpacks to. `Description::file_bytes` and `content_hash` are the packed
/// file's own.
#[derive(Debug, Serialize)]
pub struct PackedInfo {
    /// The size of the raw field that `vlf-bake unpack` writes.
    pub unpacked_bytes: u64,
    /// Its content hash.
    pub unpacked_content_hash: String,
    /// `unpacked_bytes / file_bytes`.
    pub ratio: f64,
}

/// Describes a field from its header, table and small sections.
pub fn describe(r: &FieldReader<'_>) -> Description {
    let h = r.header;
    let p = r.params;
    let s = r.scene;
    let sections = section_infos(r.table);
    let inputs = r
        .inputs
        .iter()
        .map(|i| InputInfo {
            name: r.string(i.name_offset, i.name_length).unwrap_or("<invalid name>").to_string(),
            triangles: i.triangle_count,
            file_hash: hex(&i.file_hash),
        })
        .collect();
    Description {
        format_version: format!("{}.{}", h.version_major, h.version_minor),
        content_hash: hex(&h.content_hash),
        input_hash: hex(&h.input_hash),
        file_bytes: h.file_length,
        triangle_count: s.triangle_count,
        dropped_degenerate: s.dropped_degenerate,
        direction_count: p.direction_count,
        lattice_n: p.lattice_n,
        tile_resolution: p.tile_resolution,
        leaf_size: p.leaf_size,
        max_depth: p.max_depth,
        requested_directions: p.requested_directions(),
        requested_tiles: p.requested_tiles(),
        max_bytes: p.max_bytes,
        max_bytes_per_triangle: p.max_bytes_per_triangle,
        margin: p.margin,
        center: s.center,
        radius: s.radius,
        aabb_min: s.aabb_min,
        aabb_max: s.aabb_max,
        // Rounded: libm trigonometry may differ in the last bits across platforms.
        worst_direction_angle_deg: (Lattice::new(p.lattice_n).worst_angle().to_degrees() * 1e6).round() / 1e6,
        statistics: Statistics::from_record(r.statistics),
        inputs,
        sources: r.sources.len(),
        materials: r.materials.len(),
        cameras: r.cameras.len(),
        lights: r.lights.len(),
        sections,
        packed: None,
    }
}

/// Describes a field decoded from a packed file (`vlf_runtime::Field::packed_layout`): the
/// description of the decoded field, with the file's size, content hash and sections as stored.
pub fn describe_packed(r: &FieldReader<'_>, layout: &PackedLayout) -> Description {
    let mut d = describe(r);
    d.packed = Some(PackedInfo {
        unpacked_bytes: d.file_bytes,
        unpacked_content_hash: d.content_hash,
        ratio: d.file_bytes as f64 / layout.header.file_length as f64,
    });
    d.file_bytes = layout.header.file_length;
    d.content_hash = hex(&layout.header.content_hash);
    d.sections = section_infos(&layout.table);
    d
}

fn section_infos(table: &[vlf_format::SectionEntry]) -> Vec<SectionInfo> {
    table
        .iter()
        .map(|e| SectionInfo {
            kind: e.kind,
            name: kind_name(e.kind),
            codec: if e.codec == codec::RAW { "raw" } else { "zstd" },
            offset: e.offset,
            stored_length: e.stored_length,
            raw_length: e.raw_length,
            element_size: e.element_size,
            elements: e.raw_length / e.element_size.max(1) as u64,
            raw_hash: hex(&e.raw_hash),
        })
        .collect()
}

/// The full verification: every byte (`vlf_format::verify`) plus the geometric sections against
/// the lattice and frames they must equal (`formats/vlf.md` §5.3–5.4).
pub fn verify(
    r: &FieldReader<'_>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<vlf_format::VerifyReport, FormatError> {
    let report = vlf_format::verify(r, progress)?;
    let lattice = Lattice::new(r.params.lattice_n);
    let bad = |section: SectionKind, problem: String| FormatError::Invalid { section: section.name(), problem };
    if r.lookup != lattice.lookup_table().as_slice() {
        return Err(bad(SectionKind::Lookup, "does not match the lattice of §5.3".into()));
    }
    for (j, d) in lattice.directions().into_iter().enumerate() {
        let stored = r.directions[j];
        if stored != [d[0] as f32, d[1] as f32, d[2] as f32, 0.0] {
            return Err(bad(SectionKind::Directions, format!("direction {j} is {stored:?}, the lattice gives {d:?}")));
        }
        if r.rotations[j] != frame(d) {
            return Err(bad(SectionKind::Rotations, format!("rotation {j} differs from the frame of §5.4")));
        }
    }
    Ok(report)
}
