//! Full verification (§7, second paragraph): every hash, padding byte, reserved field, offset and
//! index. Time is linear in the file size; the first fault is returned, naming where it is.
//!
//! Geometric facts (that DIRECTIONS, LOOKUP and ROTATIONS are the lattice of §5.3–5.4) are not
//! checked here: this crate knows bytes, not geometry. `vlf-bake dump --verify` adds those checks.

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
    pub ids: u64,
}

fn invalid(section: &'static str, problem: String) -> FormatError {
    FormatError::Invalid { section, problem }
}

/// Verifies everything in `field`. `progress(done, total)` is called with bytes processed.
pub fn verify(field: &FieldReader<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<VerifyReport, FormatError> {
    let total = field.bytes.len() as u64;
    let mut report = VerifyReport { sections: field.table.len(), ..Default::default() };

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
            report.bytes_hashed += chunk.len() as u64;
            progress(report.bytes_hashed, total);
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

    check_reserved(field)?;
    check_beams_tiles_leaves(field, &mut report)?;
    check_triangles_and_provenance(field)?;
    check_materials(field)?;
    check_cameras(field)?;
    check_lights(field)?;
    check_statistics(field)?;
    progress(total, total);
    Ok(report)
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
    if f.scene.reserved != [0; 3] {
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

fn check_beams_tiles_leaves(f: &FieldReader<'_>, report: &mut VerifyReport) -> Result<(), FormatError> {
    let n2 = f.params.tile_resolution as usize * f.params.tile_resolution as usize;
    let tri_count = f.triangles.len() as u64;
    let (mut leaf_base, mut id_base) = (0u64, 0u64);
    for (j, beam) in f.beams.iter().enumerate() {
        let bad = |problem: String| invalid("BEAMS", format!("direction {j}: {problem}"));
        if beam.leaf_base != leaf_base || beam.id_base != id_base {
            return Err(bad(format!(
                "leaf_base {} / id_base {} do not follow the previous direction (expected {leaf_base} / {id_base})",
                beam.leaf_base, beam.id_base
            )));
        }
        if beam.id_count > u32::MAX as u64 || beam.leaf_count > u32::MAX as u64 {
            return Err(bad("leaf_count or id_count exceeds 2^32 - 1".into()));
        }
        let bounds_end = leaf_base + beam.leaf_count + 1;
        let ids_end = id_base + beam.id_count;
        if bounds_end > f.leaf_bounds.len() as u64 || ids_end > f.triangle_ids.len() as u64 {
            return Err(bad("leaves or ids run past the end of LEAF_BOUNDS or TRIANGLE_IDS".into()));
        }
        let bounds = &f.leaf_bounds[leaf_base as usize..bounds_end as usize];
        let ids = &f.triangle_ids[id_base as usize..ids_end as usize];
        if bounds[0] != 0 || *bounds.last().unwrap() as u64 != beam.id_count {
            return Err(invalid("LEAF_BOUNDS", format!("direction {j}: bounds do not run from 0 to id_count")));
        }
        if let Some(k) = bounds.windows(2).position(|w| w[0] > w[1]) {
            return Err(invalid("LEAF_BOUNDS", format!("direction {j}: bound {k} decreases")));
        }
        let tiles = &f.tiles[j * n2..(j + 1) * n2];
        let mut next_leaf = 0u64;
        for (i, tile) in tiles.iter().enumerate() {
            let bad = |problem: String| invalid("TILES", format!("direction {j}, tile {i}: {problem}"));
            if tile.first_leaf as u64 != next_leaf {
                return Err(bad(format!("first_leaf {} should be {next_leaf}", tile.first_leaf)));
            }
            if tile.depth as u32 > f.params.max_depth || tile.reserved != [0; 3] {
                return Err(bad(format!("depth {} exceeds max_depth or reserved bytes set", tile.depth)));
            }
            let leaves = 1u64 << tile.depth;
            let first = tile.first_leaf as usize;
            if next_leaf + leaves > beam.leaf_count {
                return Err(bad("leaves run past the direction's leaf_count".into()));
            }
            let tile_bounds = &bounds[first..first + leaves as usize + 1];
            let empty = tile_bounds[0] == tile_bounds[leaves as usize];
            if tile.is_empty() != empty || (empty && (tile.depth != 0 || *tile != TileRecord::empty(tile.first_leaf))) {
                return Err(bad("empty-tile encoding is inconsistent with its leaves".into()));
            }
            for w in tile_bounds.windows(2) {
                let leaf = &ids[w[0] as usize..w[1] as usize];
                if let Some(&id) = leaf.iter().find(|&&id| id as u64 >= tri_count) {
                    return Err(invalid(
                        "TRIANGLE_IDS",
                        format!("direction {j}, tile {i}: id {id} >= triangle_count {tri_count}"),
                    ));
                }
                if leaf.windows(2).any(|p| p[0] >= p[1]) {
                    return Err(invalid(
                        "TRIANGLE_IDS",
                        format!("direction {j}, tile {i}: ids in a leaf are not strictly increasing"),
                    ));
                }
            }
            next_leaf += leaves;
        }
        if next_leaf != beam.leaf_count {
            return Err(invalid(
                "TILES",
                format!("direction {j}: tiles hold {next_leaf} leaves, BEAMS says {}", beam.leaf_count),
            ));
        }
        report.tiles += n2 as u64;
        report.ids += beam.id_count;
        leaf_base = bounds_end;
        id_base = ids_end;
    }
    if leaf_base != f.leaf_bounds.len() as u64 || id_base != f.triangle_ids.len() as u64 {
        return Err(invalid("BEAMS", "directions do not cover LEAF_BOUNDS and TRIANGLE_IDS exactly".into()));
    }
    Ok(())
}

fn check_triangles_and_provenance(f: &FieldReader<'_>) -> Result<(), FormatError> {
    for (i, t) in f.triangles.iter().enumerate() {
        if t.v.iter().any(|v| v[3] != 0.0 || !v[..3].iter().all(|c| c.is_finite())) {
            return Err(invalid(
                "TRIANGLES",
                format!("triangle {i}: a coordinate is not finite or padding is not zero"),
            ));
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

/// Recounts STATISTICS from the tiles. Only sound after `check_beams_tiles_leaves` passed.
fn recount_statistics(f: &FieldReader<'_>) -> StatisticsRecord {
    let n2 = f.params.tile_resolution as usize * f.params.tile_resolution as usize;
    let mut s = StatisticsRecord::zeroed_record();
    s.tile_count = f.tiles.len() as u64;
    for (j, beam) in f.beams.iter().enumerate() {
        let bounds = &f.leaf_bounds[beam.leaf_base as usize..];
        let ids = &f.triangle_ids[beam.id_base as usize..];
        for tile in &f.tiles[j * n2..(j + 1) * n2] {
            if tile.is_empty() {
                s.empty_tiles += 1;
                continue;
            }
            let first = tile.first_leaf as usize;
            let leaves = 1usize << tile.depth;
            let lo = bounds[first] as usize;
            let hi = bounds[first + leaves] as usize;
            let distinct = count_distinct(&ids[lo..hi]);
            s.tile_triangle_sum += distinct;
            s.max_tile_triangles = s.max_tile_triangles.max(distinct as u32);
            s.max_depth_used = s.max_depth_used.max(tile.depth as u32);
            s.depth_histogram[tile.depth as usize] += 1;
        }
        s.leaf_count += beam.leaf_count;
        s.id_count += beam.id_count;
    }
    s
}

/// Distinct values in a tile's ids (each leaf sorted; a triangle may sit in several leaves).
fn count_distinct(ids: &[u32]) -> u64 {
    let mut v = ids.to_vec();
    v.sort_unstable();
    v.dedup();
    v.len() as u64
}

fn check_statistics(f: &FieldReader<'_>) -> Result<(), FormatError> {
    let recount = recount_statistics(f);
    if recount != *f.statistics {
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
