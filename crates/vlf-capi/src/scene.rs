//! What a field carries for rendering besides geometry, from C: its materials (and the material of
//! a triangle), its glTF cameras and its lights (`formats/vlf.md` §5.10–5.12). A field without
//! them (every format 1.0 field) has none: counts of 0, and `VLF_NO_INDEX` for a triangle's
//! material. Names point into the field, as provenance strings do.

use crate::boundary::*;
use crate::types::*;
use vlf_runtime::{CameraProjection, LightKind, Material, SceneCamera, SceneLight};

fn material_record(m: &Material<'_>) -> VlfMaterial {
    VlfMaterial {
        name: m.name.as_ptr().cast(),
        name_len: m.name.len(),
        input: m.input,
        index: m.index,
        diffuse: m.diffuse,
        shininess: m.shininess,
        specular: m.specular,
        ior: m.ior,
        reflection: m.reflection,
        transmission: m.transmission,
        emission: m.emission,
    }
}

fn camera_record(c: &SceneCamera<'_>) -> VlfCamera {
    let (projection, yfov, aspect_ratio, xmag, ymag) = match c.projection {
        CameraProjection::Perspective { yfov, aspect_ratio } => {
            (VLF_CAMERA_PERSPECTIVE, yfov, aspect_ratio.unwrap_or(0.0), 0.0, 0.0)
        }
        CameraProjection::Orthographic { xmag, ymag } => (VLF_CAMERA_ORTHOGRAPHIC, 0.0, 0.0, xmag, ymag),
    };
    VlfCamera {
        name: c.name.as_ptr().cast(),
        name_len: c.name.len(),
        projection,
        yfov,
        aspect_ratio,
        xmag,
        ymag,
        position: c.position,
        forward: c.forward,
        up: c.up,
        znear: c.znear,
        zfar: c.zfar.unwrap_or(0.0),
        input: c.input,
        camera: c.camera,
        node: c.node,
    }
}

fn light_record(l: &SceneLight<'_>) -> VlfLight {
    let (kind, inner_cone, outer_cone) = match l.kind {
        LightKind::Point => (VLF_LIGHT_POINT, 0.0, 0.0),
        LightKind::Spot { inner_cone, outer_cone } => (VLF_LIGHT_SPOT, inner_cone, outer_cone),
        LightKind::Directional => (VLF_LIGHT_DIRECTIONAL, 0.0, 0.0),
    };
    VlfLight {
        name: l.name.as_ptr().cast(),
        name_len: l.name.len(),
        kind,
        position: l.position,
        direction: l.direction,
        color: l.color,
        intensity: l.intensity,
        range: l.range.unwrap_or(0.0),
        inner_cone,
        outer_cone,
        input: l.input,
        light: l.light,
        node: l.node,
    }
}

/// The number of materials the field holds, in `*count`; indices run from 0 to `count − 1`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_material_count(field: *const VlfField, count: *mut u32) -> VlfStatus {
    call("vlf_material_count", || {
        // SAFETY: the caller's promises.
        let (field, count) = unsafe { (field_arg(field)?, out(count, "count")?) };
        count.write(count_u32(field.materials().len()));
        Ok(())
    })
}

/// Material number `index` of the field, in `*material`. Its name points into the field and stays
/// valid until `vlf_close`; it is not NUL-terminated.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if `index` is not below `vlf_material_count` (or a
/// pointer is misaligned); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `field` must be NULL or an open handle; `material` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_material(field: *const VlfField, index: u32, material: *mut VlfMaterial) -> VlfStatus {
    call("vlf_material", || {
        // SAFETY: the caller's promises.
        let (field, material) = unsafe { (field_arg(field)?, out(material, "material")?) };
        let mut all = field.materials();
        index_range(index, all.len(), "materials")?;
        let m = all.nth(index as usize).ok_or_else(|| Failure::invalid(format!("no material {index}")))?;
        material.write(material_record(&m));
        Ok(())
    })
}

/// The index (for `vlf_material`) of the material of triangle `prim`, in `*index`:
/// `VLF_NO_INDEX` if the triangle has none, or the field holds no record of it (a format 1.0
/// field holds none), in which case a renderer uses a default surface.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if `prim` is not below the triangle count (or a
/// pointer is misaligned); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `field` must be NULL or an open handle; `index` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_triangle_material(field: *const VlfField, prim: u32, index: *mut u32) -> VlfStatus {
    call("vlf_triangle_material", || {
        // SAFETY: the caller's promises.
        let (field, index) = unsafe { (field_arg(field)?, out(index, "index")?) };
        triangle_range(field, prim)?;
        index.write(field.material_index(prim).map_or(VLF_NO_INDEX, count_u32));
        Ok(())
    })
}

/// The number of cameras the field holds (from its glTF inputs, in node order), in `*count`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_camera_count(field: *const VlfField, count: *mut u32) -> VlfStatus {
    call("vlf_camera_count", || {
        // SAFETY: the caller's promises.
        let (field, count) = unsafe { (field_arg(field)?, out(count, "count")?) };
        count.write(count_u32(field.cameras().count()));
        Ok(())
    })
}

/// Camera number `index` of the field, in `*camera`. Its name points into the field and stays
/// valid until `vlf_close`; it is not NUL-terminated.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if `index` is not below `vlf_camera_count` (or a
/// pointer is misaligned); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `field` must be NULL or an open handle; `camera` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_camera(field: *const VlfField, index: u32, camera: *mut VlfCamera) -> VlfStatus {
    call("vlf_camera", || {
        // SAFETY: the caller's promises.
        let (field, camera) = unsafe { (field_arg(field)?, out(camera, "camera")?) };
        index_range(index, field.cameras().count(), "cameras")?;
        let c = field.cameras().nth(index as usize).ok_or_else(|| Failure::invalid(format!("no camera {index}")))?;
        camera.write(camera_record(&c));
        Ok(())
    })
}

/// The number of punctual lights the field holds (from its glTF inputs, in node order), in
/// `*count`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_light_count(field: *const VlfField, count: *mut u32) -> VlfStatus {
    call("vlf_light_count", || {
        // SAFETY: the caller's promises.
        let (field, count) = unsafe { (field_arg(field)?, out(count, "count")?) };
        count.write(count_u32(field.lights().count()));
        Ok(())
    })
}

/// Light number `index` of the field, in `*light`. Its name points into the field and stays
/// valid until `vlf_close`; it is not NUL-terminated.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if `index` is not below `vlf_light_count` (or a
/// pointer is misaligned); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `field` must be NULL or an open handle; `light` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_light(field: *const VlfField, index: u32, light: *mut VlfLight) -> VlfStatus {
    call("vlf_light", || {
        // SAFETY: the caller's promises.
        let (field, light) = unsafe { (field_arg(field)?, out(light, "light")?) };
        index_range(index, field.lights().count(), "lights")?;
        let l = field.lights().nth(index as usize).ok_or_else(|| Failure::invalid(format!("no light {index}")))?;
        light.write(light_record(&l));
        Ok(())
    })
}
