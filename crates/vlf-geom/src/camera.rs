//! A pinhole camera: the primary-ray generator shared by `trace` ray files, benchmarks and the
//! renderer, so every method is measured on the same rays.

use crate::ray::Ray;

/// A pinhole camera. Image coordinates run from the top-left corner, x right, y down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The pinhole: the origin of every primary ray.
    pub eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt())
}

impl Camera {
    /// A camera at `eye` looking at `target`, `up` roughly up, vertical field of view `vfov_deg`,
    /// image aspect `width / height`.
    pub fn look_at(eye: [f64; 3], target: [f64; 3], up: [f64; 3], vfov_deg: f64, aspect: f64) -> Self {
        let forward = normalize(sub(target, eye));
        let mut right = cross(forward, up);
        if right.iter().all(|c| c.abs() < 1e-12) {
            right = cross(forward, [1.0, 0.0, 0.0]);
        }
        let right = normalize(right);
        let up = cross(right, forward);
        let half_h = (vfov_deg.to_radians() / 2.0).tan();
        let half_w = half_h * aspect;
        Camera { eye, forward, right: scale(right, half_w), up: scale(up, half_h) }
    }

    /// The paper's outside viewpoint (Figure 3): looking at the centre of a bounding sphere from
    /// 2.5 radii away, with a field of view that frames the whole sphere.
    pub fn outside(center: [f64; 3], radius: f64, aspect: f64) -> Self {
        let dir = normalize([0.45, 0.3, 1.0]);
        let eye =
            [center[0] + dir[0] * 2.5 * radius, center[1] + dir[1] * 2.5 * radius, center[2] + dir[2] * 2.5 * radius];
        // The sphere subtends asin(1/2.5) = 23.6° half-angle; 50° leaves a small border.
        Camera::look_at(eye, center, [0.0, 1.0, 0.0], 50.0, aspect)
    }

    /// The paper's inside viewpoint (Figure 3): near the centre of the scene, looking across it.
    pub fn inside(center: [f64; 3], radius: f64, aspect: f64) -> Self {
        let eye = [center[0] - 0.1 * radius, center[1] + 0.05 * radius, center[2] - 0.15 * radius];
        let target = [center[0] + radius, center[1] + 0.2 * radius, center[2] + 0.6 * radius];
        Camera::look_at(eye, target, [0.0, 1.0, 0.0], 70.0, aspect)
    }

    /// The unit view direction (towards the image centre).
    pub fn forward(&self) -> [f64; 3] {
        self.forward
    }

    /// The unit direction of the image's x axis (right).
    pub fn right(&self) -> [f64; 3] {
        normalize(self.right)
    }

    /// The unit direction of the image's upward axis.
    pub fn up(&self) -> [f64; 3] {
        normalize(self.up)
    }

    /// The ray through image point `(x, y)`, both in `[0, 1]`.
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let sx = 2.0 * x - 1.0;
        let sy = 1.0 - 2.0 * y;
        let d: [f64; 3] = std::array::from_fn(|i| self.forward[i] + sx * self.right[i] + sy * self.up[i]);
        let d = normalize(d);
        Ray::new(self.eye.map(|c| c as f32), d.map(|c| c as f32))
    }

    /// One ray through the centre of each pixel of a `width × height` image, row by row.
    pub fn primary_rays(&self, width: u32, height: u32) -> Vec<Ray> {
        let mut rays = Vec::with_capacity(width as usize * height as usize);
        for py in 0..height {
            for px in 0..width {
                rays.push(self.ray((px as f64 + 0.5) / width as f64, (py as f64 + 0.5) / height as f64));
            }
        }
        rays
    }
}
