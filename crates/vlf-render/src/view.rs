//! Where primary rays come from: a pinhole (`vlf_geom::Camera`, shared with `vlf-bake rays` and
//! the benchmarks) or an orthographic view, placed by flags, by a framing rule, or by a glTF
//! camera the field carries.

use crate::math::{V3, cross, madd, normalize, widen};
use vlf_geom::{Camera, Ray};
use vlf_runtime::{CameraProjection, SceneCamera};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Projection {
    Pinhole(Camera),
    /// Rays parallel to `forward` from the image plane through `eye`, `half_width` and
    /// `half_height` world units either side.
    Orthographic {
        half_width: f64,
        half_height: f64,
    },
}

/// A camera: primary rays for image points, and the frame that default lights are placed in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    projection: Projection,
    /// Eye point and unit frame: view direction, image right and image up.
    pub eye: V3,
    pub forward: V3,
    pub right: V3,
    pub up: V3,
    /// The primary rays' interval (a glTF camera's near and far planes).
    tmin: f32,
    tmax: f32,
}

impl View {
    fn pinhole(camera: Camera) -> View {
        View {
            projection: Projection::Pinhole(camera),
            eye: camera.eye,
            forward: camera.forward(),
            right: camera.right(),
            up: camera.up(),
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// A pinhole at `eye` looking at `target`, `up` roughly up, vertical field of view
    /// `vfov_degrees`, image aspect `width / height`.
    pub fn look_at(eye: V3, target: V3, up: V3, vfov_degrees: f64, aspect: f64) -> View {
        View::pinhole(Camera::look_at(eye, target, up, vfov_degrees, aspect))
    }

    /// The paper's outside viewpoint (`vlf-bake rays --view outside`): the whole bounding sphere
    /// in view.
    pub fn outside(center: V3, radius: f64, aspect: f64) -> View {
        View::pinhole(Camera::outside(center, radius, aspect))
    }

    /// The paper's inside viewpoint (`vlf-bake rays --view inside`; its Figure 5, right).
    pub fn inside(center: V3, radius: f64, aspect: f64) -> View {
        View::pinhole(Camera::inside(center, radius, aspect))
    }

    /// A camera of the field for an image of aspect `width / height` (a perspective camera's own
    /// aspect ratio is for choosing the image size; the image's aspect is used here). `None` if
    /// its frame is degenerate (a damaged field).
    pub fn from_scene_camera(c: &SceneCamera<'_>, aspect: f64) -> Option<View> {
        let eye = widen(c.position);
        let forward = normalize(widen(c.forward))?;
        let up_hint = normalize(widen(c.up))?;
        if !eye.iter().all(|v| v.is_finite()) {
            return None;
        }
        let right = normalize(cross(forward, up_hint))?;
        let up = cross(right, forward);
        let tmin = if c.znear.is_finite() && c.znear >= 0.0 { c.znear } else { 0.0 };
        let tmax = c.zfar.filter(|z| z.is_finite() && *z > tmin).unwrap_or(f32::INFINITY);
        let projection = match c.projection {
            CameraProjection::Perspective { yfov, .. } => {
                let degrees = (yfov as f64).to_degrees();
                if !(degrees > 0.0 && degrees < 180.0) {
                    return None;
                }
                Projection::Pinhole(Camera::look_at(eye, madd(eye, forward, 1.0), up, degrees, aspect))
            }
            CameraProjection::Orthographic { xmag, ymag } => {
                let (half_width, half_height) = (xmag as f64, ymag as f64);
                if !(half_width > 0.0 && half_height > 0.0 && half_width.is_finite() && half_height.is_finite()) {
                    return None;
                }
                Projection::Orthographic { half_width, half_height }
            }
        };
        Some(View { projection, eye, forward, right, up, tmin, tmax })
    }

    /// The primary ray through image point `(x, y)`, both in `[0, 1]` from the top-left corner.
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let mut ray = match self.projection {
            Projection::Pinhole(camera) => camera.ray(x, y),
            Projection::Orthographic { half_width, half_height } => {
                let origin = madd(
                    madd(self.eye, self.right, (2.0 * x - 1.0) * half_width),
                    self.up,
                    (1.0 - 2.0 * y) * half_height,
                );
                Ray::new(origin.map(|c| c as f32), self.forward.map(|c| c as f32))
            }
        };
        ray.tmin = self.tmin;
        ray.tmax = self.tmax;
        ray
    }
}
