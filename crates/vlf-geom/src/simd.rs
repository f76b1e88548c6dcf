//! The triangle test of [`crate::triangle`] on four triangles at once: the vector twins of
//! [`TriRay::candidate`], chosen by an instruction-set token ([`Isa`]).
//!
//! Every lane does the scalar test's operations on its own triangle, in the scalar order, with
//! no fused multiply-add (Rust never contracts `a * b + c`), so each lane's answer is the scalar
//! answer to the bit: IEEE operations round the same in a vector lane. Tests hold every twin to
//! the scalar test on awkward triangles and rays (`kernel.rs`).
//!
//! - [`Baseline`]: what every CPU of the target has. On x86-64, SSE2 (part of the target's
//!   baseline): two triangles per instruction. Elsewhere the scalar test, four times.
//! - [`Avx2`] (x86-64 only): four triangles per instruction. A value of it exists only once
//!   [`Avx2::detect`] has seen the CPU support AVX2, which is what makes its use sound. Code that
//!   wants it inlined compiles its loop with `#[target_feature(enable = "avx2")]` (the runtime's
//!   query does); called from elsewhere it is still correct, only slower.

use crate::triangle::{Candidate, TriRay};

/// A triangle's three vertices, as the kernel reads them.
pub type Tri = [[f32; 3]; 3];

/// An instruction set the four-triangle test may use, as a token: holding a value means the
/// CPU supports it.
pub trait Isa: Copy {
    /// [`TriRay::candidate`] of four triangles: lane `i` is `candidate(tris[i])`, to the bit.
    fn candidates4(self, ray: &TriRay, tris: [&Tri; 4]) -> [Option<Candidate>; 4];

    /// [`Isa::candidates4`] where only the first `n` lanes matter (the others may be `None`).
    #[inline(always)]
    fn candidates_first(self, ray: &TriRay, tris: [&Tri; 4], n: usize) -> [Option<Candidate>; 4] {
        let _ = n;
        self.candidates4(ray, tris)
    }
}

/// The instructions every CPU of the target has: SSE2 on x86-64 (two triangles at a time), the
/// scalar test elsewhere.
#[derive(Clone, Copy, Debug, Default)]
pub struct Baseline;

impl Isa for Baseline {
    #[inline(always)]
    fn candidates4(self, ray: &TriRay, tris: [&Tri; 4]) -> [Option<Candidate>; 4] {
        let [a, b] = candidates2(ray, tris[0], tris[1]);
        let [c, d] = candidates2(ray, tris[2], tris[3]);
        [a, b, c, d]
    }

    #[inline(always)]
    fn candidates_first(self, ray: &TriRay, tris: [&Tri; 4], n: usize) -> [Option<Candidate>; 4] {
        if n <= 2 {
            let [a, b] = candidates2(ray, tris[0], tris[1]);
            [a, b, None, None]
        } else {
            self.candidates4(ray, tris)
        }
    }
}

/// [`TriRay::candidate`] of two triangles at once, each of SSE2's two f64 lanes doing the scalar
/// operations of one triangle in the same order.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[inline(always)]
pub(crate) fn candidates2(ray: &TriRay, p: &Tri, q: &Tri) -> [Option<Candidate>; 2] {
    use std::arch::x86_64::*;
    // SAFETY: these intrinsics need SSE2, which every x86-64 CPU has (it is in the target's
    // baseline features); they read and write only their register arguments.
    let (mask, t, u, v) = unsafe {
        let [kx, ky, kz] = ray.k;
        let org = ray.org.map(|o| _mm_set1_pd(o));
        // Vertex `i`'s component `k` of both triangles (lane 0: `p`), relative to the origin.
        let rel = |i: usize, k: usize, o: __m128d| _mm_sub_pd(_mm_set_pd(q[i][k] as f64, p[i][k] as f64), o);
        let vertex = |i: usize| [rel(i, kx, org[0]), rel(i, ky, org[1]), rel(i, kz, org[2])];
        let (a, b, c) = (vertex(0), vertex(1), vertex(2));
        let (sx, sy) = (_mm_set1_pd(ray.sx), _mm_set1_pd(ray.sy));
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
        let sz = _mm_set1_pd(ray.sz);
        let (az, bz, cz) = (_mm_mul_pd(sz, a[2]), _mm_mul_pd(sz, b[2]), _mm_mul_pd(sz, c[2]));
        let rcp = _mm_div_pd(_mm_set1_pd(1.0), det);
        let sum = _mm_add_pd(_mm_add_pd(_mm_mul_pd(u, az), _mm_mul_pd(v, bz)), _mm_mul_pd(w, cz));
        let lanes = |x: __m128d| -> [f64; 2] { [_mm_cvtsd_f64(x), _mm_cvtsd_f64(_mm_unpackhi_pd(x, x))] };
        (mask, lanes(_mm_mul_pd(sum, rcp)), lanes(_mm_mul_pd(v, rcp)), lanes(_mm_mul_pd(w, rcp)))
    };
    std::array::from_fn(|i| (mask & 1 << i != 0).then(|| Candidate { t: t[i], u: u[i], v: v[i] }))
}

/// [`TriRay::candidate`] of two triangles, on targets without a vector twin.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
pub(crate) fn candidates2(ray: &TriRay, p: &Tri, q: &Tri) -> [Option<Candidate>; 2] {
    [ray.candidate(p), ray.candidate(q)]
}

/// AVX-512 (F, VL, BW and DQ, with AVX2): the four-triangle test of [`Avx2`], for code compiled
/// with the 32 vector registers AVX-512 brings (the runtime's queries keep more of their state in
/// registers). Only [`Avx512::detect`] makes one.
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

impl Avx512 {
    /// The token, if this CPU supports AVX-512 F, VL, BW and DQ and AVX2 (always `None` off
    /// x86-64).
    pub fn detect() -> Option<Avx512> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx2")
        {
            return Some(Avx512(()));
        }
        None
    }

    /// The AVX2 token: a CPU with this one has AVX2.
    pub fn avx2(self) -> Avx2 {
        Avx2(())
    }
}

impl Isa for Avx512 {
    #[inline(always)]
    fn candidates4(self, ray: &TriRay, tris: [&Tri; 4]) -> [Option<Candidate>; 4] {
        self.avx2().candidates4(ray, tris)
    }

    #[inline(always)]
    fn candidates_first(self, ray: &TriRay, tris: [&Tri; 4], n: usize) -> [Option<Candidate>; 4] {
        self.avx2().candidates_first(ray, tris, n)
    }
}

/// AVX2: four triangles per instruction. Only [`Avx2::detect`] makes one.
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

impl Avx2 {
    /// The token, if this CPU supports AVX2 (always `None` off x86-64).
    pub fn detect() -> Option<Avx2> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Some(Avx2(()));
        }
        None
    }
}

impl Isa for Avx2 {
    #[inline(always)]
    fn candidates4(self, ray: &TriRay, tris: [&Tri; 4]) -> [Option<Candidate>; 4] {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a value of `Avx2` exists only after `Avx2::detect` saw AVX2 on this CPU.
        #[allow(unsafe_code)]
        unsafe {
            candidates4_avx2(ray, tris)
        }
        #[cfg(not(target_arch = "x86_64"))]
        Baseline.candidates4(ray, tris)
    }

    #[inline(always)]
    fn candidates_first(self, ray: &TriRay, tris: [&Tri; 4], n: usize) -> [Option<Candidate>; 4] {
        if n <= 2 {
            let [a, b] = candidates2(ray, tris[0], tris[1]);
            [a, b, None, None]
        } else {
            self.candidates4(ray, tris)
        }
    }
}

/// [`TriRay::candidate`] of four triangles, one per AVX2 f64 lane, each in the scalar order.
///
/// Always inlined, and not itself compiled for AVX2: inlined into a caller that is (the
/// runtime's queries), its intrinsics become single instructions; from any other caller they are
/// calls, slower but the same.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[inline(always)]
unsafe fn candidates4_avx2(ray: &TriRay, tris: [&Tri; 4]) -> [Option<Candidate>; 4] {
    use std::arch::x86_64::*;
    // SAFETY: the CPU supports AVX2 (the caller's promise), which these intrinsics need; the
    // loads read 8 of the 9 f32 of a live triangle and the store writes a local array of four
    // f64. Everything else reads and writes only registers.
    unsafe {
        // The nine f32 components of each triangle, transposed to nine vectors of four lanes (lane
        // `i`: triangle `i`), then widened to f64 exactly. The first eight of a triangle are one
        // unaligned load of its first 32 bytes (a record is 36 bytes, so the load stays inside it).
        let load = |t: &Tri| {
            let p: *const f32 = t.as_ptr().cast();
            // `t` is 9 contiguous f32 (`[[f32; 3]; 3]` has no padding); 8 are read.
            _mm256_loadu_ps(p)
        };
        let (r0, r1, r2, r3) = (load(tris[0]), load(tris[1]), load(tris[2]), load(tris[3]));
        let t0 = _mm256_unpacklo_ps(r0, r1);
        let t1 = _mm256_unpackhi_ps(r0, r1);
        let t2 = _mm256_unpacklo_ps(r2, r3);
        let t3 = _mm256_unpackhi_ps(r2, r3);
        // Components (0, 4), (1, 5), (2, 6), (3, 7) of the four triangles: low and high halves.
        let c04 = _mm256_shuffle_ps::<0b01_00_01_00>(t0, t2);
        let c15 = _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2);
        let c26 = _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3);
        let c37 = _mm256_shuffle_ps::<0b11_10_11_10>(t1, t3);
        let lo = |x: __m256| _mm256_cvtps_pd(_mm256_castps256_ps128(x));
        let hi = |x: __m256| _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(x));
        let c8 = _mm256_cvtps_pd(_mm_set_ps(tris[3][2][2], tris[2][2][2], tris[1][2][2], tris[0][2][2]));
        // Component `3·vertex + axis`.
        let comp = [lo(c04), lo(c15), lo(c26), lo(c37), hi(c04), hi(c15), hi(c26), hi(c37), c8];
        let [kx, ky, kz] = ray.k;
        let org = ray.org.map(|o| _mm256_set1_pd(o));
        let vertex = |i: usize| {
            [
                _mm256_sub_pd(comp[3 * i + kx], org[0]),
                _mm256_sub_pd(comp[3 * i + ky], org[1]),
                _mm256_sub_pd(comp[3 * i + kz], org[2]),
            ]
        };
        let (a, b, c) = (vertex(0), vertex(1), vertex(2));
        let (sx, sy) = (_mm256_set1_pd(ray.sx), _mm256_set1_pd(ray.sy));
        let ax = _mm256_sub_pd(a[0], _mm256_mul_pd(sx, a[2]));
        let ay = _mm256_sub_pd(a[1], _mm256_mul_pd(sy, a[2]));
        let bx = _mm256_sub_pd(b[0], _mm256_mul_pd(sx, b[2]));
        let by = _mm256_sub_pd(b[1], _mm256_mul_pd(sy, b[2]));
        let cx = _mm256_sub_pd(c[0], _mm256_mul_pd(sx, c[2]));
        let cy = _mm256_sub_pd(c[1], _mm256_mul_pd(sy, c[2]));

        let u = _mm256_sub_pd(_mm256_mul_pd(cx, by), _mm256_mul_pd(cy, bx));
        let v = _mm256_sub_pd(_mm256_mul_pd(ax, cy), _mm256_mul_pd(ay, cx));
        let w = _mm256_sub_pd(_mm256_mul_pd(bx, ay), _mm256_mul_pd(by, ax));
        // Ordered, non-signalling comparisons: false for a NaN, as the scalar `<` and `>` are.
        let zero = _mm256_setzero_pd();
        let lt = |x: __m256d| _mm256_cmp_pd::<_CMP_LT_OQ>(x, zero);
        let gt = |x: __m256d| _mm256_cmp_pd::<_CMP_GT_OQ>(x, zero);
        let neg = _mm256_or_pd(_mm256_or_pd(lt(u), lt(v)), lt(w));
        let pos = _mm256_or_pd(_mm256_or_pd(gt(u), gt(v)), gt(w));
        let det = _mm256_add_pd(_mm256_add_pd(u, v), w);
        let reject = _mm256_or_pd(_mm256_and_pd(neg, pos), _mm256_cmp_pd::<_CMP_EQ_OQ>(det, zero));
        let mask = !_mm256_movemask_pd(reject) & 0b1111;
        if mask == 0 {
            return [None; 4];
        }
        let sz = _mm256_set1_pd(ray.sz);
        let (az, bz, cz) = (_mm256_mul_pd(sz, a[2]), _mm256_mul_pd(sz, b[2]), _mm256_mul_pd(sz, c[2]));
        let rcp = _mm256_div_pd(_mm256_set1_pd(1.0), det);
        let sum = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(u, az), _mm256_mul_pd(v, bz)), _mm256_mul_pd(w, cz));
        let lanes = |x: __m256d| -> [f64; 4] {
            let mut out = [0.0; 4];
            // `out` is four f64, 32 bytes; an unaligned store.
            _mm256_storeu_pd(out.as_mut_ptr(), x);
            out
        };
        let (t, u, v) = (lanes(_mm256_mul_pd(sum, rcp)), lanes(_mm256_mul_pd(v, rcp)), lanes(_mm256_mul_pd(w, rcp)));
        std::array::from_fn(|i| (mask & 1 << i != 0).then(|| Candidate { t: t[i], u: u[i], v: v[i] }))
    }
}
