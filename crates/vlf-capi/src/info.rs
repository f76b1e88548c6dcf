//! What a field says about itself, from C: its format version, the box around its scene, whether it
//! was stored packed, and the parameters it was baked with.

use crate::boundary::*;
use crate::types::*;

/// The field's format version (`formats/vlf.md` §3.4) in `*major` and `*minor`: 1.0 holds
/// geometry and provenance, 1.1 adds materials, cameras and lights.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer,
/// or `major` and `minor` at the same address).
///
/// # Safety
/// `field` must be NULL or an open handle; `major` and `minor` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_format_version(field: *const VlfField, major: *mut u16, minor: *mut u16) -> VlfStatus {
    call("vlf_format_version", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(major, 1, "major")?;
        check_array(minor, 1, "minor")?;
        check_disjoint(span(major, 1), span(minor, 1), "arguments `major` and `minor`")?;
        // SAFETY: the caller's promises; the outputs do not overlap (checked).
        let (major, minor) = unsafe { (out(major, "major")?, out(minor, "minor")?) };
        let (a, b) = field.format_version();
        major.write(a);
        minor.write(b);
        Ok(())
    })
}

/// The corners of the box around every vertex of the scene, in world units: `min[0..3]` and
/// `max[0..3]`. Tighter than the bounding sphere; use it to frame the scene.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer,
/// or overlapping arrays).
///
/// # Safety
/// `field` must be NULL or an open handle; `min` and `max` NULL or room for 3 doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_bounds(field: *const VlfField, min: *mut f64, max: *mut f64) -> VlfStatus {
    call("vlf_bounds", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(min, 3, "min")?;
        check_array(max, 3, "max")?;
        check_disjoint(span(min, 3), span(max, 3), "arrays `min` and `max`")?;
        // SAFETY: the caller's promises; the outputs do not overlap (checked).
        let (min, max) = unsafe { (slice_out(min, 3, "min")?, slice_out(max, 3, "max")?) };
        let (lo, hi) = field.bounds();
        write_all(min, &lo);
        write_all(max, &hi);
        Ok(())
    })
}

/// Whether the field was stored packed (`vlf-bake pack`, zstd sections) and so was decoded into
/// memory when it was opened: 1 in `*packed` if so, 0 for a raw field (mapped, opened in constant
/// time). A packed field's bytes, hashes and answers are those of the raw field.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `packed` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_is_packed(field: *const VlfField, packed: *mut u8) -> VlfStatus {
    call("vlf_is_packed", || {
        // SAFETY: the caller's promises.
        let (field, packed) = unsafe { (field_arg(field)?, out(packed, "packed")?) };
        packed.write(field.is_packed() as u8);
        Ok(())
    })
}

/// The parameters the field was baked with (`formats/vlf.md` §5.2), in `*parameters`: the
/// directions and tiles chosen and asked for (`VLF_AUTOMATIC` if the baker chose them), the leaf
/// policy, the margin and the size budgets.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `parameters` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_parameters(field: *const VlfField, parameters: *mut VlfParameters) -> VlfStatus {
    call("vlf_parameters", || {
        // SAFETY: the caller's promises.
        let (field, parameters) = unsafe { (field_arg(field)?, out(parameters, "parameters")?) };
        let p = field.parameters();
        parameters.write(VlfParameters {
            margin: p.margin,
            max_bytes: p.max_bytes,
            max_bytes_per_triangle: p.max_bytes_per_triangle,
            lattice_n: p.lattice_n,
            directions: p.directions,
            tiles: p.tiles,
            leaf_size: p.leaf_size,
            max_depth: p.max_depth,
            requested_directions: p.requested_directions.unwrap_or(VLF_AUTOMATIC),
            requested_tiles: p.requested_tiles.unwrap_or(VLF_AUTOMATIC),
            reserved: 0,
        });
        Ok(())
    })
}
