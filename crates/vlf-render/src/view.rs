//! Where primary rays come from: a pinhole (`vlf_geom::Camera`, shared with `vlf-bake rays` and
//! the benchmarks) or an orthographic view, placed by flags, by a framing rule, or by a glTF
//! camera the field carries.

use crate::framing::{self, OUTSIDE_FOV_DEGREES};
use crate::math::{V3, cross, madd, normalize, sub, widen};
use vlf_geom::{Camera, Ray};
use vlf_runtime::{CameraProjection, Field, SceneCamera};

/// Where a scene is: its bounding sphere and its box, as a field stores them
/// (`Field::bounding_sphere`, `Field::bounds`). The framings of [`View::outside`] and
/// [`View::inside`] are computed from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneBounds {
    pub center: V3,
    pub radius: f64,
    /// The corners of the box around every vertex.
    pub min: V3,
    pub max: V3,
}

impl SceneBounds {
    /// The bounds `field` stores.
    pub fn of(field: &Field) -> SceneBounds {
        let ((center, radius), (min, max)) = (field.bounding_sphere(), field.bounds());
        SceneBounds { center, radius, min, max }
    }

    /// The bounds of the box `min..max`, with the sphere around it.
    pub fn of_box(min: V3, max: V3) -> SceneBounds {
        let center = std::array::from_fn(|i| (min[i] + max[i]) / 2.0);
        let radius = crate::math::length(crate::math::sub(max, min)) / 2.0;
        SceneBounds { center, radius, min, max }
    }

    /// The spacing of f32 numbers at the scene's farthest coordinate from the origin: rays are
    /// f32 (`Ray`, the rays files of `formats/rays.md`), so their origins cannot be placed more
    /// finely than this anywhere in the scene.
    pub fn f32_spacing(&self) -> f64 {
        let far = (0..3).map(|i| self.min[i].abs().max(self.max[i].abs())).fold(0.0f64, f64::max) as f32;
        (far.next_up() - far) as f64
    }

    /// A warning when world-space f32 rays cannot resolve the scene: fewer than
    /// [`MIN_F32_STEPS`] steps of f32 across its diameter. A mesh far from the origin bakes (the
    /// field stores it relative to its centre), but world rays aimed at it land on a coarse grid:
    /// a triangle 1 unit across at x = 10⁹, where f32 numbers are 64 apart, was hit by none of
    /// 307,200 primary rays. For the rays files of `vlf-bake rays` (world rays by their format)
    /// and pictures traced with world rays (a tracer whose origin is the world's, such as a scene
    /// of instances); [`crate::render`] traces a field relative to its centre, which resolves it.
    pub fn f32_warning(&self) -> Option<String> {
        let (spacing, across) = (self.f32_spacing(), 2.0 * self.radius);
        let far = (0..3).map(|i| self.center[i].abs()).fold(0.0f64, f64::max);
        (across < MIN_F32_STEPS * spacing).then(|| {
            format!(
                "the scene is {across:.3e} across and {far:.3e} from the origin, where the rays' f32 coordinates are \
                 {spacing:.3e} apart: rays cannot resolve it and may miss it; move the mesh near the origin before baking"
            )
        })
    }
}

/// The fewest f32 steps across a scene's diameter below which [`SceneBounds::f32_warning`] warns:
/// a ray then starts within a thousandth of the scene's size of where it was aimed.
pub const MIN_F32_STEPS: f64 = 1000.0;

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

    /// The outside viewpoint (`vlf-bake rays --view outside`, the default of `render`): from the
    /// paper's direction, the scene's whole box in view in both directions of the picture, close
    /// up (`crate::framing`; a very thin box is seen along an axis). A damaged field's box falls
    /// back on its bounding sphere, framed in both directions too.
    pub fn outside(bounds: &SceneBounds, aspect: f64) -> View {
        match framing::outside(bounds.min, bounds.max, aspect) {
            Some(p) => View::look_at(p.eye, p.target, p.up, OUTSIDE_FOV_DEGREES, aspect),
            None => {
                // The paper's distance, 2.5 radii, where the sphere subtends asin(1/2.5); the
                // narrower of the two fields of view must hold it, with the same border.
                let camera = Camera::outside(bounds.center, bounds.radius, aspect);
                let half = (1.0f64 / 2.5).asin().tan() / 0.95 / aspect.min(1.0);
                let vfov = 2.0 * half.atan().to_degrees();
                View::look_at(camera.eye, bounds.center, [0.0, 1.0, 0.0], vfov, aspect)
            }
        }
    }

    /// The paper's inside viewpoint (`vlf-bake rays --view inside`; its Figure 5, right): near the
    /// centre of the bounding sphere, looking across the scene.
    pub fn inside(bounds: &SceneBounds, aspect: f64) -> View {
        View::pinhole(Camera::inside(bounds.center, bounds.radius, aspect))
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
        self.ray_relative_to([0.0; 3], x, y)
    }

    /// [`View::ray`] with its origin given relative to `origin` (a tracer's,
    /// `vlf_geom::Intersector::origin`): the eye less `origin` in f64, then rounded to f32, so a
    /// scene far from the world's origin is seen with the precision of its own size. The world
    /// ray, bit for bit, when `origin` is zero.
    pub fn ray_relative_to(&self, origin: V3, x: f64, y: f64) -> Ray {
        let eye = sub(self.eye, origin);
        let mut ray = match self.projection {
            Projection::Pinhole(camera) => Ray { org: eye.map(|c| c as f32), ..camera.ray(x, y) },
            Projection::Orthographic { half_width, half_height } => {
                let start =
                    madd(madd(eye, self.right, (2.0 * x - 1.0) * half_width), self.up, (1.0 - 2.0 * y) * half_height);
                Ray::new(start.map(|c| c as f32), self.forward.map(|c| c as f32))
            }
        };
        ray.tmin = self.tmin;
        ray.tmax = self.tmax;
        ray
    }
}

#[cfg(test)]
mod f32_tests {
    use super::*;

    #[test]
    fn far_small_scenes_are_warned_of_and_near_ones_are_not() {
        let at = |x: f64, size: f64| SceneBounds::of_box([x, 0.0, 0.0], [x, size, size]);
        // At 10⁹ f32 numbers are 64 apart: a scene 1 unit across is not resolved.
        assert_eq!(at(1e9, 1.0).f32_spacing(), 64.0);
        let w = at(1e9, 1.0).f32_warning().expect("a warning");
        assert!(w.starts_with("the scene is 1.414e0 across and 1.000e9 from the origin"), "{w}");
        assert!(w.contains("6.400e1 apart"), "{w}");
        // Near the origin, or large enough for its distance, no warning.
        assert_eq!(at(0.0, 1.0).f32_warning(), None);
        assert_eq!(at(1e9, 1e6).f32_warning(), None);
        // The bunny's size at 10⁴ (f32 spacing 2⁻¹⁰): 0.14 units are 145 steps, warned.
        assert!(at(1e4, 0.1).f32_warning().is_some());
        assert_eq!(at(1e2, 0.1).f32_warning(), None);
    }
}
