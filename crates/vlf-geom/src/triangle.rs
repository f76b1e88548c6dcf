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
    org: [f64; 3],
    /// The axes of the sheared frame: `kz` the ray's dominant axis.
    k: [usize; 3],
    sx: f64,
    sy: f64,
    sz: f64,
    /// The ray's `tmin`: hits before it are rejected.
    pub tmin: f64,
}

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
        TriRay { org, k: [kx, ky, kz], sx: d[kx] * sz, sy: d[ky] * sz, sz, tmin: ray.tmin as f64 }
    }

    /// Tests one triangle; a hit must have `tmin ≤ t ≤ tmax`.
    #[inline(always)]
    pub fn intersect(&self, v0: [f32; 3], v1: [f32; 3], v2: [f32; 3], tmax: f32) -> Option<TriHit> {
        self.candidate(&[v0, v1, v2])?.within(self.tmin, tmax)
    }

    /// The test of one triangle up to its range test: where the ray's line meets the triangle,
    /// if it does. The plain twin of [`Self::candidates`].
    #[inline(always)]
    pub(crate) fn candidate(&self, tri: &[[f32; 3]; 3]) -> Option<Candidate> {
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

    /// [`Self::candidate`] of two triangles at once, each lane of SSE2's two f64 lanes doing the
    /// scalar operations of one triangle in the same order, so that both answers are the scalar
    /// ones to the bit (IEEE operations round the same in a vector lane; nothing is fused).
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    #[inline(always)]
    pub(crate) fn candidates(&self, p: &[[f32; 3]; 3], q: &[[f32; 3]; 3]) -> [Option<Candidate>; 2] {
        use std::arch::x86_64::*;
        // SAFETY: these intrinsics need SSE2, which every x86-64 CPU has (it is in the target's
        // baseline features); they read and write only their register arguments.
        let (mask, t, u, v) = unsafe {
            let [kx, ky, kz] = self.k;
            let org = self.org.map(|o| _mm_set1_pd(o));
            // Vertex `i`'s component `k` of both triangles (lane 0: `p`), relative to the origin.
            let rel = |i: usize, k: usize, o: __m128d| _mm_sub_pd(_mm_set_pd(q[i][k] as f64, p[i][k] as f64), o);
            let vertex = |i: usize| [rel(i, kx, org[0]), rel(i, ky, org[1]), rel(i, kz, org[2])];
            let (a, b, c) = (vertex(0), vertex(1), vertex(2));
            let (sx, sy) = (_mm_set1_pd(self.sx), _mm_set1_pd(self.sy));
            let ax = _mm_sub_pd(a[0], _mm_mul_pd(sx, a[2]));
            let ay = _mm_sub_pd(a[1], _mm_mul_pd(sy, a[2]));
            let bx = _mm_sub_pd(b[0], _mm_mul_pd(sx, b[2]));
            let by = _mm_sub_pd(b[1], _mm_mul_pd(sy, b[2]));
            let cx = _mm_sub_pd(c[0], _mm_mul_pd(sx, c[2]));
            let cy = _mm_sub_pd(c[1], _mm_mul_pd(sy, c[2]));

            let u = _mm_sub_pd(_mm_mul_pd(cx, by), _mm_mul_pd(cy, bx));
            let v = _mm_sub_pd(_mm_mul_pd(ax, cy), _mm_mul_pd(ay, cx));
            let w = _mm_sub_pd(_mm_mul_pd(bx, ay), _mm_mul_pd(by, ax));
            // Ordered comparisons: false for a NaN, as the scalar `<` and `>` are.
            let zero = _mm_setzero_pd();
            let neg = _mm_or_pd(_mm_or_pd(_mm_cmplt_pd(u, zero), _mm_cmplt_pd(v, zero)), _mm_cmplt_pd(w, zero));
            let pos = _mm_or_pd(_mm_or_pd(_mm_cmpgt_pd(u, zero), _mm_cmpgt_pd(v, zero)), _mm_cmpgt_pd(w, zero));
            let det = _mm_add_pd(_mm_add_pd(u, v), w);
            let reject = _mm_or_pd(_mm_and_pd(neg, pos), _mm_cmpeq_pd(det, zero));
            let mask = !_mm_movemask_pd(reject) & 0b11;
            if mask == 0 {
                return [None, None];
            }
            let sz = _mm_set1_pd(self.sz);
            let (az, bz, cz) = (_mm_mul_pd(sz, a[2]), _mm_mul_pd(sz, b[2]), _mm_mul_pd(sz, c[2]));
            let rcp = _mm_div_pd(_mm_set1_pd(1.0), det);
            let sum = _mm_add_pd(_mm_add_pd(_mm_mul_pd(u, az), _mm_mul_pd(v, bz)), _mm_mul_pd(w, cz));
            let lanes = |x: __m128d| -> [f64; 2] { [_mm_cvtsd_f64(x), _mm_cvtsd_f64(_mm_unpackhi_pd(x, x))] };
            (mask, lanes(_mm_mul_pd(sum, rcp)), lanes(_mm_mul_pd(v, rcp)), lanes(_mm_mul_pd(w, rcp)))
        };
        std::array::from_fn(|i| (mask & 1 << i != 0).then(|| Candidate { t: t[i], u: u[i], v: v[i] }))
    }

    /// [`Self::candidate`] of two triangles, on targets without a vector twin.
    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    pub(crate) fn candidates(&self, p: &[[f32; 3]; 3], q: &[[f32; 3]; 3]) -> [Option<Candidate>; 2] {
        [self.candidate(p), self.candidate(q)]
    }
}

/// Where a ray's line meets a triangle, before the test of `t` against the ray's range: `t` and
/// the barycentrics of `v1` and `v2`, in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub(crate) t: f64,
    pub(crate) u: f64,
    pub(crate) v: f64,
}

impl Candidate {
    /// The hit, rounded to f32, if `tmin ≤ t ≤ tmax` (compared before rounding).
    #[inline(always)]
    pub(crate) fn within(self, tmin: f64, tmax: f32) -> Option<TriHit> {
        if !(self.t >= tmin && self.t <= tmax as f64) {
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
