//! The CAMERAS and LIGHTS records of glTF cameras and `KHR_lights_punctual` lights
//! (`formats/vlf.md` §5.11, §5.12), checked against the ranges glTF allows.

use ::gltf as gl;
use vlf_format::{CameraRecord, LightRecord, camera_kind, light_kind};

/// The CAMERAS record of a camera (names are filled in by the builder), or `None` if its
/// parameters are outside glTF's ranges.
pub(super) fn camera_record(
    camera: &gl::json::camera::Camera,
    camera_index: u32,
    node: u32,
    position: [f64; 3],
    forward: [f64; 3],
    up: [f64; 3],
    input: u32,
) -> Option<CameraRecord> {
    use gl::json::camera::Type;
    use gl::json::validation::Checked;
    let ok = |v: f32| v.is_finite() && v >= 0.0;
    let mut record = CameraRecord {
        kind: 0,
        input,
        camera: camera_index,
        node,
        name_offset: 0,
        name_length: 0,
        position: position.map(|c| c as f32),
        forward: forward.map(|c| c as f32),
        up: up.map(|c| c as f32),
        yfov: 0.0,
        aspect_ratio: 0.0,
        znear: 0.0,
        zfar: 0.0,
        xmag: 0.0,
        ymag: 0.0,
        reserved: 0,
    };
    match camera.type_ {
        Checked::Valid(Type::Perspective) => {
            let p = camera.perspective.as_ref()?;
            let (aspect, zfar) = (p.aspect_ratio.unwrap_or(0.0), p.zfar.unwrap_or(0.0));
            if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI && ok(aspect) && ok(p.znear) && ok(zfar)) {
                return None;
            }
            record.kind = camera_kind::PERSPECTIVE;
            (record.yfov, record.aspect_ratio, record.znear, record.zfar) = (p.yfov, aspect, p.znear, zfar);
        }
        Checked::Valid(Type::Orthographic) => {
            let o = camera.orthographic.as_ref()?;
            let (xmag, ymag) = (o.xmag.abs(), o.ymag.abs());
            if !(xmag > 0.0 && ymag > 0.0 && xmag.is_finite() && ymag.is_finite() && ok(o.znear) && ok(o.zfar)) {
                return None;
            }
            record.kind = camera_kind::ORTHOGRAPHIC;
            (record.xmag, record.ymag, record.znear, record.zfar) = (xmag, ymag, o.znear, o.zfar);
        }
        Checked::Invalid => return None,
    }
    Some(record)
}

/// The LIGHTS record of a `KHR_lights_punctual` light, or `None` if its parameters are outside
/// the extension's ranges.
pub(super) fn light_record(
    light: &gl::json::extensions::scene::khr_lights_punctual::Light,
    light_index: u32,
    node: u32,
    position: [f64; 3],
    direction: [f64; 3],
    input: u32,
) -> Option<LightRecord> {
    use gl::json::extensions::scene::khr_lights_punctual::Type;
    use gl::json::validation::Checked;
    let ok = |v: f32| v.is_finite() && v >= 0.0;
    let range = light.range.unwrap_or(0.0);
    if !(light.color.iter().all(|&c| ok(c)) && ok(light.intensity) && ok(range)) {
        return None;
    }
    let (kind, inner, outer) = match light.type_ {
        Checked::Valid(Type::Point) => (light_kind::POINT, 0.0, 0.0),
        Checked::Valid(Type::Directional) => (light_kind::DIRECTIONAL, 0.0, 0.0),
        Checked::Valid(Type::Spot) => {
            let spot = light.spot.as_ref()?;
            let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
            if !(inner >= 0.0 && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
                return None;
            }
            (light_kind::SPOT, inner, outer)
        }
        Checked::Invalid => return None,
    };
    Some(LightRecord {
        kind,
        input,
        light: light_index,
        node,
        name_offset: 0,
        name_length: 0,
        position: position.map(|c| c as f32),
        direction: direction.map(|c| c as f32),
        color: light.color,
        intensity: light.intensity,
        range,
        inner_cone: inner,
        outer_cone: outer,
        reserved: 0,
    })
}
