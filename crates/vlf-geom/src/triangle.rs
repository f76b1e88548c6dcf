//! The watertight ray/triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013.
//!
//! The ray is translated to the origin, sheared and scaled so that it runs along +z; the 2D edge
//! functions of the transformed triangle decide the hit. Each vertex is transformed on its own, so
//! two triangles that share an edge evaluate that edge with the same operands and opposite signs:
//! a ray through a shared edge hits at least one of them. When an edge function is exactly zero it
//! is recomputed in f64, as the paper prescribes, so the sign of such a tie is exact.
//!
//! Triangles are double-sided (no backface culling).

use crate::ray::Ray;

/// Per-ray constants of the test, computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct TriRay {
    org: [f32; 3],
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
    pub tmin: f32,
}

/// The result of one test: parameter and barycentrics of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl TriRay {
    /// Precomputes the shear for `ray`. The ray must be valid ([`Ray::is_valid`]).
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let a = [d[0].abs(), d[1].abs(), d[2].abs()];
        let kz = if a[0] > a[1] {
            if a[0] > a[2] { 0 } else { 2 }
        } else if a[1] > a[2] {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding of the transformed triangle independent of the direction's sign.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        TriRay {
            org: ray.org,
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            tmin: ray.tmin,
        }
    }

    /// Tests one triangle; a hit must have `tmin ≤ t ≤ tmax`.
    #[inline(always)]
    pub fn intersect(&self, v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], tmax: f32) -> Option<TriHit> {
        let o = self.org;
        let a = [v0[0] - o[0], v0[1] - o[1], v0[2] - o[2]];
        let b = [v1[0] - o[0], v1[1] - o[1], v1[2] - o[2]];
        let c = [v2[0] - o[0], v2[1] - o[1], v2[2] - o[2]];
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];

        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let rcp = 1.0 / det;
        let t = t_scaled * rcp;
        if !(t >= self.tmin && t <= tmax) {
            return None;
        }
        Some(TriHit { t, u: v * rcp, v: w * rcp })
    }
}

/// Whether a triangle has zero area exactly (its edge cross product is zero in f64, which is
/// exact for f32 inputs up to rounding of the products). Such triangles can never be hit by the
/// watertight test and are dropped at import.
pub fn is_degenerate(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> bool {
    let e1: [f64; 3] = std::array::from_fn(|i| v1[i] as f64 - v0[i] as f64);
    let e2: [f64; 3] = std::array::from_fn(|i| v2[i] as f64 - v0[i] as f64);
    let c = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    c == [0.0; 3]
}
