//! Full verification (§7, second paragraph): every hash, padding byte, reserved field, offset and
//! index. Time is linear in the file size; the first fault is returned, naming where it is.
//!
//! Geometric facts (that DIRECTIONS, LOOKUP and ROTATIONS are the lattice of §5.3–5.4) are not
//! checked here: this crate knows bytes, not geometry. `vlf-bake dump --verify` adds those checks.

use crate::block::Block;
use crate::error::{FormatError, hex};
use crate::layout::*;
use crate::reader::FieldReader;
use crate::section::*;

/// What a successful verification looked at.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct VerifyReport {
    pub bytes_hashed: u64,
    pub sections: usize,
    pub tiles: u64,
    /// Refs checked.
    pub ids: u64,
}

fn invalid(section: &'static str, problem: String) -> FormatError {
    FormatError::Invalid { section, problem }
}

/// Verifies everything in `field`. `progress(done, total)` is called with bytes processed.
pub fn verify(field: &FieldReader<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<VerifyReport, FormatError> {
    let total = field.bytes.len() as u64;
    let mut report = VerifyReport { sections: field.table.len(), ..Default::default() };
    report.bytes_hashed = verify_hashes(field, progress)?;
    check_reserved(field)?;
    let recount = check_beams_tiles_leaves(field, &mut report)?;
    check_triangles_and_provenance(field)?;
    check_materials(field)?;
    check_cameras(field)?;
    check_lights(field)?;
    check_duplicates(field)?;
    check_statistics(field, &recount)?;
    progress(total, total);
    Ok(report)
}

/// Every section's bytes against its `raw_hash`, and the padding before each section zero: the
/// check that no byte of the file changed since it was written, without the structural checks of
/// [`verify`]. Returns the bytes hashed; `progress(done, total)` is called as they are. Time is
/// linear in the file size.
pub fn verify_hashes(field: &FieldReader<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<u64, FormatError> {
    let total = field.bytes.len() as u64;
    let mut hashed = 0;
    // Hashes, in chunks so progress moves on big sections.
    let mut pos = (HEADER_SIZE + TABLE_ENTRY_SIZE * field.table.len()) as u64;
    for e in field.table {
        check_zero(field.bytes, pos, e.offset)?;
        let stored = &field.bytes[e.offset as usize..(e.offset + e.stored_length) as usize];
        if e.codec != codec::RAW {
            return Err(FormatError::CompressedSection {
                kind: SectionKind::from_u32(e.kind).map_or("unknown", |k| k.name()),
                codec: e.codec,
            });
        }
        let mut hasher = blake3::Hasher::new();
        for chunk in stored.chunks(16 << 20) {
            hasher.update(chunk);
            hashed += chunk.len() as u64;
            progress(hashed, total);
        }
        let computed = *hasher.finalize().as_bytes();
        if computed != e.raw_hash {
            return Err(FormatError::SectionHashMismatch {
                kind: kind_name(e.kind),
                stored: hex(&e.raw_hash),
                computed: hex(&computed),
            });
        }
        pos = e.offset + e.stored_length;
    }
    Ok(hashed)
}

fn check_zero(bytes: &[u8], from: u64, to: u64) -> Result<(), FormatError> {
    for (i, &b) in bytes[from as usize..to as usize].iter().enumerate() {
        if b != 0 {
            return Err(FormatError::NonZeroPadding { offset: from + i as u64, value: b });
        }
    }
    Ok(())
}

fn check_reserved(f: &FieldReader<'_>) -> Result<(), FormatError> {
    if f.scene.reserved != 0 {
        return Err(invalid("SCENE", "reserved fields are not zero".into()));
    }
    if f.params.reserved0 != 0 || f.params.reserved1 != 0 {
        return Err(invalid("PARAMS", "reserved fields are not zero".into()));
    }
    if f.statistics.reserved != [0; 10] {
        return Err(invalid("STATISTICS", "reserved fields are not zero".into()));
    }
    if let Some(j) = f.directions.iter().position(|d| d[3] != 0.0) {
        return Err(invalid("DIRECTIONS", format!("direction {j}: fourth component is not zero")));
    }
    for (i, s) in f.sources.iter().enumerate() {
        if s.input >= f.inputs.len() as u32 {
            return Err(invalid("SOURCES", format!("source {i}: input {} out of range", s.input)));
        }
        if f.string(s.name_offset, s.name_length).is_none() {
            return Err(invalid("SOURCES", format!("source {i}: name is out of bounds or not UTF-8")));
        }
    }
    for (i, input) in f.inputs.iter().enumerate() {
        if f.string(input.name_offset, input.name_length).is_none() {
            return Err(invalid("INPUTS", format!("input {i}: name is out of bounds or not UTF-8")));
        }
    }
    if std::str::from_utf8(f.strings).is_err() {
        return Err(invalid("STRINGS", "not UTF-8".into()));
    }
    Ok(())
}

/// BEAMS, TILES and LEAVES (§5.5, §5.6): directions laid out without gaps, each tile's block
/// where its entry says, blocks in tile order without gaps, every block's invariants
/// ([`Block::check`]); and the STATISTICS those tiles add up to, for [`check_statistics`].
fn check_beams_tiles_leaves(f: &FieldReader<'_>, report: &mut VerifyReport) -> Result<StatisticsRecord, FormatError> {
    let n2 = f.params.tile_resolution as usize * f.params.tile_resolution as usize;
    let tri_count = f.triangles.len() as u64;
    let max_leaves = 1u64 << f.params.max_depth;
    let mut stats = StatisticsRecord::zeroed_record();
    stats.tile_count = f.tiles.len() as u64;
    let mut base = 0u64;
    for (j, beam) in f.beams.iter().enumerate() {
        let bad = |problem: String| invalid("BEAMS", format!("direction {j}: {problem}"));
        if beam.leaves_base != base {
            return Err(bad(format!(
                "leaves_base {} does not follow the previous direction (expected {base})",
                beam.leaves_base
            )));
        }
        if beam.leaves_words > u32::MAX as u64 {
            return Err(bad(format!("leaves_words {} exceeds 2^32 - 1", beam.leaves_words)));
        }
        let end = base + beam.leaves_words;
        if end > f.leaves.len() as u64 {
            return Err(bad("its blocks run past the end of LEAVES".into()));
        }
        let words = &f.leaves[base as usize..end as usize];
        let (mut next, mut leaves, mut refs) = (0u64, 0u64, 0u64);
        for (i, &entry) in f.tiles[j * n2..(j + 1) * n2].iter().enumerate() {
            let bad = |section: &'static str, problem: String| {
                invalid(section, format!("direction {j}, tile {i}: {problem}"))
            };
            if entry == EMPTY_TILE {
                stats.empty_tiles += 1;
                continue;
            }
            if entry as u64 != next {
                return Err(bad("TILES", format!("block at word {entry}, expected {next} (blocks follow tile order)")));
            }
            let block = Block::parse(&words[next as usize..])
                .ok_or_else(|| bad("LEAVES", "the block's header does not fit in its direction's words".into()))?;
            let k = block.leaf_count() as u64;
            if k > max_leaves {
                return Err(bad("LEAVES", format!("{k} leaves, over 2^max_depth = {max_leaves}")));
            }
            let distinct = block.check(tri_count).map_err(|problem| bad("LEAVES", problem))?;
            next += block.words() as u64;
            leaves += k;
            refs += block.ref_count() as u64;
            let depth = k.next_power_of_two().trailing_zeros();
            stats.tile_triangle_sum += distinct;
            stats.max_tile_triangles = stats.max_tile_triangles.max(distinct as u32);
            stats.max_depth_used = stats.max_depth_used.max(depth);
            stats.depth_histogram[depth as usize] += 1;
        }
        if next != beam.leaves_words {
            return Err(bad(format!("its blocks take {next} words, leaves_words says {}", beam.leaves_words)));
        }
        if leaves != beam.leaf_count || refs != beam.ref_count {
            return Err(bad(format!(
                "its blocks hold {leaves} leaves and {refs} refs, BEAMS says {} and {}",
                beam.leaf_count, beam.ref_count
            )));
        }
        stats.leaf_count += leaves;
        stats.id_count += refs;
        report.tiles += n2 as u64;
        report.ids += refs;
        base = end;
    }
    if base != f.leaves.len() as u64 {
        return Err(invalid("BEAMS", "directions do not cover LEAVES exactly".into()));
    }
    Ok(stats)
}

fn check_triangles_and_provenance(f: &FieldReader<'_>) -> Result<(), FormatError> {
    for (i, t) in f.triangles.iter().enumerate() {
        if !t.v.iter().flatten().all(|c| c.is_finite()) {
            return Err(invalid("TRIANGLES", format!("triangle {i}: a coordinate is not finite")));
        }
    }
    for (i, p) in f.provenance.iter().enumerate() {
        if p.source >= f.sources.len() as u32 {
            return Err(invalid("PROVENANCE", format!("triangle {i}: source {} out of range", p.source)));
        }
    }
    Ok(())
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

fn non_negative(values: &[f32]) -> bool {
    values.iter().all(|&v| v >= 0.0)
}

/// Whether `v` has unit length to within the rounding of a normalised f32 vector.
fn unit(v: [f32; 3]) -> bool {
    let len = (v.iter().map(|&c| c as f64 * c as f64).sum::<f64>()).sqrt();
    (len - 1.0).abs() <= 1e-4
}

/// MATERIALS (§5.10): inputs and names in range, keys strictly increasing, values finite and in
/// their domains, reserved fields zero.
fn check_materials(f: &FieldReader<'_>) -> Result<(), FormatError> {
    let mut previous: Option<(u32, u32)> = None;
    for (i, m) in f.materials.iter().enumerate() {
        let bad = |problem: &str| invalid("MATERIALS", format!("material {i}: {problem}"));
        if m.input >= f.inputs.len() as u32 {
            return Err(bad(&format!("input {} out of range", m.input)));
        }
        if previous.is_some_and(|p| p >= (m.input, m.index)) {
            return Err(bad("(input, index) is not greater than the previous material's"));
        }
        previous = Some((m.input, m.index));
        if f.string(m.name_offset, m.name_length).is_none() {
            return Err(bad("name is out of bounds or not UTF-8"));
        }
        let colours = [m.diffuse, m.specular, m.reflection, m.transmission, m.emission];
        if !colours.iter().all(|c| finite(c)) || !finite(&[m.shininess, m.ior]) {
            return Err(bad("a value is not finite"));
        }
        if !colours.iter().all(|c| non_negative(c)) || m.shininess < 0.0 || m.ior <= 0.0 {
            return Err(bad("a colour or the shininess is negative, or the index of refraction is not positive"));
        }
        if (m.reserved0, m.reserved1, m.reserved2) != (0, 0, 0) {
            return Err(bad("reserved fields are not zero"));
        }
    }
    Ok(())
}

/// CAMERAS (§5.11).
fn check_cameras(f: &FieldReader<'_>) -> Result<(), FormatError> {
    for (i, c) in f.cameras.iter().enumerate() {
        let bad = |problem: &str| invalid("CAMERAS", format!("camera {i}: {problem}"));
        if c.input >= f.inputs.len() as u32 {
            return Err(bad(&format!("input {} out of range", c.input)));
        }
        if f.string(c.name_offset, c.name_length).is_none() {
            return Err(bad("name is out of bounds or not UTF-8"));
        }
        let scalars = [c.yfov, c.aspect_ratio, c.znear, c.zfar, c.xmag, c.ymag];
        if !finite(&c.position) || !finite(&c.forward) || !finite(&c.up) || !finite(&scalars) {
            return Err(bad("a value is not finite"));
        }
        if !unit(c.forward) || !unit(c.up) {
            return Err(bad("forward or up is not a unit vector"));
        }
        if !non_negative(&scalars) {
            return Err(bad("a projection parameter is negative"));
        }
        let projection_ok = match c.kind {
            camera_kind::PERSPECTIVE => c.yfov > 0.0 && c.yfov < std::f32::consts::PI && c.xmag == 0.0 && c.ymag == 0.0,
            camera_kind::ORTHOGRAPHIC => c.xmag > 0.0 && c.ymag > 0.0 && c.yfov == 0.0 && c.aspect_ratio == 0.0,
            other => return Err(bad(&format!("unknown kind {other}"))),
        };
        if !projection_ok {
            return Err(bad("projection parameters do not fit its kind"));
        }
        if c.reserved != 0 {
            return Err(bad("reserved field is not zero"));
        }
    }
    Ok(())
}

/// LIGHTS (§5.12).
fn check_lights(f: &FieldReader<'_>) -> Result<(), FormatError> {
    for (i, l) in f.lights.iter().enumerate() {
        let bad = |problem: &str| invalid("LIGHTS", format!("light {i}: {problem}"));
        if l.input >= f.inputs.len() as u32 {
            return Err(bad(&format!("input {} out of range", l.input)));
        }
        if f.string(l.name_offset, l.name_length).is_none() {
            return Err(bad("name is out of bounds or not UTF-8"));
        }
        let scalars = [l.intensity, l.range, l.inner_cone, l.outer_cone];
        if !finite(&l.position) || !finite(&l.direction) || !finite(&l.color) || !finite(&scalars) {
            return Err(bad("a value is not finite"));
        }
        if !unit(l.direction) {
            return Err(bad("direction is not a unit vector"));
        }
        if !non_negative(&l.color) || !non_negative(&scalars) {
            return Err(bad("colour, intensity, range or a cone angle is negative"));
        }
        let cones_ok = match l.kind {
            light_kind::SPOT => l.inner_cone < l.outer_cone && l.outer_cone <= std::f32::consts::FRAC_PI_2,
            light_kind::POINT | light_kind::DIRECTIONAL => l.inner_cone == 0.0 && l.outer_cone == 0.0,
            other => return Err(bad(&format!("unknown kind {other}"))),
        };
        if !cones_ok {
            return Err(bad("cone angles do not fit its kind (spot: 0 <= inner < outer <= pi/2; others: 0)"));
        }
        if l.reserved != 0 {
            return Err(bad("reserved field is not zero"));
        }
    }
    Ok(())
}

/// DUPLICATES (§5.13): sorted by the kept triangle, each naming a triangle and a source that
/// exist, and as many as SCENE says.
fn check_duplicates(f: &FieldReader<'_>) -> Result<(), FormatError> {
    let bad = |problem: String| invalid("DUPLICATES", problem);
    if f.duplicates.len() as u64 != f.scene.dropped_duplicates {
        return Err(bad(format!(
            "{} records, SCENE counts {} merged duplicates",
            f.duplicates.len(),
            f.scene.dropped_duplicates
        )));
    }
    for (i, d) in f.duplicates.iter().enumerate() {
        if d.triangle as usize >= f.triangles.len() || d.source as usize >= f.sources.len() {
            return Err(bad(format!("record {i}: triangle {} or source {} out of range", d.triangle, d.source)));
        }
        if i > 0 && f.duplicates[i - 1].triangle > d.triangle {
            return Err(bad(format!("record {i}: not sorted by triangle")));
        }
    }
    Ok(())
}

fn check_statistics(f: &FieldReader<'_>, recount: &StatisticsRecord) -> Result<(), FormatError> {
    if recount != f.statistics {
        return Err(invalid(
            "STATISTICS",
            format!(
                "stored statistics differ from a recount of the tiles (stored {:?}, recount {:?})",
                f.statistics, recount
            ),
        ));
    }
    Ok(())
}

impl StatisticsRecord {
    /// All zeros.
    pub fn zeroed_record() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}
