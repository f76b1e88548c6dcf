//! The watertight ray/triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013.
//!
//! The ray is translated to the origin, sheared and scaled so that it runs along +z; the 2D edge
//! functions of the transformed triangle decide the hit. Each vertex is transformed on its own, so
//! two triangles that share an edge evaluate that edge from the same operands, and IEEE rounding
//! is symmetric, so the two values are exact negatives: a ray through a shared edge hits at least
//! one of them.
//!
//! Deviation from the paper: the whole test runs in f64 on the f32 vertices, instead of f32 with
//! an f64 fallback for edge functions that are exactly zero. In f32 the shear alone loses about
//! 1e-7 of a vertex's magnitude, which for a sliver 1e-4 wide is a 1e-3 error in its barycentrics
//! and in `t` (the oracle tests found this); in f64 the answer matches an f64 reference to float
//! precision. Scalar f64 arithmetic costs the same as f32 on the CPUs we target. The returned
//! `t`, `u`, `v` are rounded to f32; comparisons with `tmax` happen before rounding, and rounding
//! is monotonic, so the closest hit's rounded `t` does not depend on the order triangles are tested.
//!
//! Triangles are double-sided (no backface culling).

use crate::ray::Ray;

/// Per-ray constants of the test, computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct TriRay {
    /// The ray's origin, its components in the order `kx, ky, kz`.
    pub(crate) org: [f64; 3],
    /// The axes of the sheared frame: `kz` the ray's dominant axis.
    pub(crate) k: [usize; 3],
    pub(crate) sx: f64,
    pub(crate) sy: f64,
    pub(crate) sz: f64,
    /// The ray's `tmin`: hits before it are rejected.
    pub tmin: f64,
    /// The ray's `tmax`, at most [`T_LIMIT`]: hits after it are rejected.
    pub tmax: f64,
}

/// The largest `t` a hit can have: the largest finite f32. A hit is reported in f32, and a ray
/// whose direction is tiny against the distance to a triangle meets it at a `t` that rounds to
/// infinity there; such a hit, like any beyond `tmax`, is not a hit (else the two triangles a
/// ray meets past this limit would tie at `t = ∞`, and the farther one could win on its id).
pub const T_LIMIT: f64 = f32::MAX as f64;

/// The result of one test: parameter and barycentrics of `v1` and `v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    /// The ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of `v1`.
    pub u: f32,
    /// Barycentric weight of `v2`.
    pub v: f32,
}

impl TriRay {
    /// Precomputes the shear for `ray`. The ray must be valid ([`Ray::is_valid`]).
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        Self::relative(ray, [0.0; 3])
    }

    /// [`TriRay::new`] for triangles whose vertices are stored relative to `origin` (a field's
    /// centre, `formats/vlf.md` §5.7): the ray's origin becomes `ray.org − origin`, computed in
    /// f64, so a scene far from the world's origin keeps the precision of its own size.
    #[inline]
    pub fn relative(ray: &Ray, origin: [f64; 3]) -> Self {
        let d = ray.dir.map(f64::from);
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
        let org = [kx, ky, kz].map(|i| ray.org[i] as f64 - origin[i]);
        // One division: the shear is a product with its reciprocal (as the paper's code does).
        let sz = 1.0 / d[kz];
        TriRay {
            org,
            k: [kx, ky, kz],
            sx: d[kx] * sz,
            sy: d[ky] * sz,
            sz,
            tmin: ray.tmin as f64,
            tmax: ray.tmax.min(f32::MAX) as f64,
        }
    }

    /// Tests one triangle; a hit must have `tmin ≤ t ≤ tmax` (and `t ≤` [`T_LIMIT`]).
    #[inline(always)]
    pub fn intersect(&self, v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], tmax: f32) -> Option<TriHit> {
        self.candidate(&[v0, v1, v2])?.within(self.tmin, (tmax as f64).min(self.tmax))
    }

    /// The test of one triangle up to its range test: where the ray's line meets the triangle,
    /// if it does. The plain twin of every vector test ([`crate::simd`]).
    #[inline(always)]
    pub fn candidate(&self, tri: &[[f32; 3]; 3]) -> Option<Candidate> {
        // Each vertex relative to the ray's origin, its components picked in the frame's order as
        // they are read (indexing the vertex in memory, not an array of registers).
        let [ox, oy, oz] = self.org;
        let [kx, ky, kz] = self.k;
        let rel = |v: &[f32; 3]| [v[kx] as f64 - ox, v[ky] as f64 - oy, v[kz] as f64 - oz];
        let (a, b, c) = (rel(&tri[0]), rel(&tri[1]), rel(&tri[2]));
        let ax = a[0] - self.sx * a[2];
        let ay = a[1] - self.sy * a[2];
        let bx = b[0] - self.sx * b[2];
        let by = b[1] - self.sy * b[2];
        let cx = c[0] - self.sx * c[2];
        let cy = c[1] - self.sy * c[2];

        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        // Evaluated whole (`|`, `&`), not short-circuited: one branch, not six data-dependent ones.
        let det = u + v + w;
        if ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0)) | (det == 0.0) {
            return None;
        }
        let az = self.sz * a[2];
        let bz = self.sz * b[2];
        let cz = self.sz * c[2];
        let rcp = 1.0 / det;
        let t = (u * az + v * bz + w * cz) * rcp;
        Some(Candidate { t, u: v * rcp, v: w * rcp })
    }
}

/// Where a ray's line meets a triangle, before the test of `t` against the ray's range: `t` and
/// the barycentrics of `v1` and `v2`, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The ray parameter.
    pub t: f64,
    /// Barycentric weight of `v1`.
    pub u: f64,
    /// Barycentric weight of `v2`.
    pub v: f64,
}

impl Candidate {
    /// The hit, rounded to f32, if `tmin ≤ t ≤ tmax` (compared before rounding).
    #[inline(always)]
    pub(crate) fn within(self, tmin: f64, tmax: f64) -> Option<TriHit> {
        if !(self.t >= tmin && self.t <= tmax) {
            return None;
        }
        Some(TriHit { t: self.t as f32, u: self.u as f32, v: self.v as f32 })
    }
}

/// Whether a triangle has zero area exactly (its edge cross product is zero in f64, which is
/// exact for f32 inputs up to rounding of the products). Such triangles can never be hit by the
/// watertight test and are dropped at import.
pub fn is_degenerate(v0: [f32; 3], v1: [f32; 3], v2: [f32; 3]) -> bool {
    let e1: [f64; 3] = std::array::from_fn(|i| v1[i] as f64 - v0[i] as f64);
    let e2: [f64; 3] = std::array::from_fn(|i| v2[i] as f64 - v0[i] as f64);
    let c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    c == [0.0; 3]
}
