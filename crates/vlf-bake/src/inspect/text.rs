//! The text form of a [`Description`]: what `vlf-bake dump` prints without `--json`.

use super::Description;
use crate::params::{count, human_bytes};

/// The text `vlf-bake dump` prints for a field: header, scene, parameters, statistics and
/// sections, one fact per line, without a final newline.
pub fn describe_text(d: &Description) -> String {
    let st = &d.statistics;
    let mut s = String::new();
    let mut line = |t: String| {
        s.push_str(&t);
        s.push('\n');
    };
    line(format!("VLF field, format {}, {} ({} bytes)", d.format_version, human_bytes(d.file_bytes), d.file_bytes));
    line(format!("  content hash  {}", d.content_hash));
    line(format!("  input hash    {}", d.input_hash));
    if let Some(p) = &d.packed {
        line(format!(
            "  packed        zstd, {:.2}× smaller than the raw field of {} ({} bytes)",
            p.ratio,
            human_bytes(p.unpacked_bytes),
            p.unpacked_bytes
        ));
        line(format!("  unpacks to    content hash {}", p.unpacked_content_hash));
    }
    line("scene".into());
    line(format!("  triangles     {} ({} degenerate dropped at import)", d.triangle_count, d.dropped_degenerate));
    line(format!(
        "  sphere        centre ({:.6}, {:.6}, {:.6}), radius {:.6}",
        d.center[0], d.center[1], d.center[2], d.radius
    ));
    line(format!("  bounds        {:?} .. {:?}", d.aabb_min, d.aabb_max));
    for i in &d.inputs {
        line(format!(
            "  input         {} ({}, blake3 {})",
            i.name,
            count(i.triangles, "triangle", "triangles"),
            &i.file_hash[..16]
        ));
    }
    line(format!(
        "  rendering     {}, {}, {} ({})",
        count(d.materials as u64, "material", "materials"),
        count(d.cameras as u64, "camera", "cameras"),
        count(d.lights as u64, "light", "lights"),
        count(d.sources as u64, "source", "sources")
    ));
    line("parameters".into());
    let req = |v: Option<u32>| v.map_or("automatic".to_string(), |v| format!("requested {v}"));
    line(format!(
        "  directions    {} (lattice N = {}; {})",
        d.direction_count,
        d.lattice_n,
        req(d.requested_directions)
    ));
    line(format!("  tiles         {}² ({})", d.tile_resolution, req(d.requested_tiles)));
    line(format!("  bsp policy    leaf size {}, max depth {}", d.leaf_size, d.max_depth));
    line(format!(
        "  budget        {} ({} per triangle for automatic parameters)",
        human_bytes(d.max_bytes),
        human_bytes(d.max_bytes_per_triangle)
    ));
    line(format!("  margin        {:.3e} (world units)", d.margin));
    line(format!("  worst angle   {:.3}° between a ray and its nearest direction", d.worst_direction_angle_deg));
    line("statistics".into());
    line(format!(
        "  triangles/tile mean {:.2} ({:.2} over non-empty tiles), max {}; {:.1}% of {} tiles empty",
        st.mean_triangles_per_tile,
        st.mean_triangles_per_nonempty_tile,
        st.max_triangles_per_tile,
        100.0 * st.empty_tile_share,
        st.tiles
    ));
    line(format!(
        "  leaf depths   mean {:.2} over non-empty tiles, max {}; histogram {:?}",
        st.mean_depth_nonempty, st.max_depth_used, st.depth_histogram
    ));
    line(format!("  ids           {} in {} leaves", st.triangle_ids, st.leaves));
    line("sections".into());
    if d.packed.is_some() {
        line(format!(
            "  {:<13} {:>5} {:>14} {:>14} {:>14} {:>7} {:>12}  {}",
            "kind", "codec", "offset", "stored", "raw", "ratio", "elements", "blake3 (raw)"
        ));
        for e in &d.sections {
            line(format!(
                "  {:<13} {:>5} {:>14} {:>14} {:>14} {:>6.2}× {:>12}  {}",
                e.name,
                e.codec,
                e.offset,
                e.stored_length,
                e.raw_length,
                e.raw_length as f64 / e.stored_length.max(1) as f64,
                e.elements,
                &e.raw_hash[..16]
            ));
        }
    } else {
        line(format!(
            "  {:<13} {:>5} {:>14} {:>14} {:>12}  {}",
            "kind", "codec", "offset", "bytes", "elements", "blake3"
        ));
        for e in &d.sections {
            line(format!(
                "  {:<13} {:>5} {:>14} {:>14} {:>12}  {}",
                e.name,
                e.codec,
                e.offset,
                e.stored_length,
                e.elements,
                &e.raw_hash[..16]
            ));
        }
    }
    s.pop();
    s
}
