//! Steps 1 and 2 of a query ([`crate::query`]): clip the ray to the scene, choose the stored
//! direction nearest to it by the constant-time lattice lookup (`formats/vlf.md` §5.3), and
//! rotate it into that direction's canonical frame (§5.4), where the walk ([`crate::trace`],
//! [`crate::walk`]) takes over.

// Comparisons are written `!(a <= b)` on purpose: a NaN (from a lying file) takes the reject
// branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::walk::{Setup, higher, lower};
use vlf_format::{FieldReader, LOOKUP_FLIP, LOOKUP_NONE, Z_LEVELS};
use vlf_geom::Ray;
use vlf_geom::frame::mul;
use vlf_geom::lattice;

/// What steps 1 and 2 read: the scene's box, the lattice and its tables, derived once at open.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Aim<'a> {
    /// The scene's box relative to the centre, grown by the margin.
    box_lo: [f64; 3],
    box_hi: [f64; 3],
    radius: f64,
    /// Quantized beam levels per world unit: `1 / z_step`.
    levels_per_unit: f64,
    /// The lattice size `N`, and `2N + 1`.
    lattice_n: u32,
    side: i64,
    /// The built-in table of nearest lattice points, for lattices of up to `FINE_MAX_N` segments.
    fine: Option<Fine>,
    lookup: &'a [u32],
    directions: &'a [[f32; 4]],
    rotations: &'a [[f64; 9]],
}

impl<'a> Aim<'a> {
    pub(crate) fn new(reader: &FieldReader<'a>) -> Self {
        let (p, s) = (reader.params, reader.scene);
        Aim {
            box_lo: s.aabb_min.map(|v| v - p.margin),
            box_hi: s.aabb_max.map(|v| v + p.margin),
            radius: s.radius,
            levels_per_unit: 1.0 / (2.0 * s.radius / Z_LEVELS as f64),
            lattice_n: p.lattice_n,
            side: 2 * p.lattice_n as i64 + 1,
            fine: Fine::new(p.lattice_n),
            lookup: reader.lookup,
            directions: reader.directions,
            rotations: reader.rotations,
        }
    }

    /// [`crate::FieldView::select_direction`].
    #[inline(always)]
    pub(crate) fn select_direction(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        let sigma = if d[2] < 0.0 { -1.0 } else { 1.0 };
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        let n = self.lattice_n as i64;
        let (ci, ck) = match self.fine {
            Some(fine) => {
                let nf = n as f64;
                let scale = nf / (ax + ay + az);
                let [a, b] = fine.point((ax * scale).min(nf), (ay * scale).min(nf));
                (a as i64, b as i64)
            }
            None => self.nearest_lattice_point([ax, ay, az]),
        };
        // The signs of `σ·d`'s x and y.
        let (sx, sy) = (if d[0] * sigma < 0.0 { -1 } else { 1 }, if d[1] * sigma < 0.0 { -1 } else { 1 });
        let entry = *self.lookup.get(((sy * ck + n) * self.side + (sx * ci + n)) as usize)?;
        let j = (entry & !LOOKUP_FLIP) as usize;
        if entry == LOOKUP_NONE || j >= self.directions.len() {
            return None;
        }
        Some((j, if entry & LOOKUP_FLIP != 0 { -sigma } else { sigma }))
    }

    /// The lattice point `(a, b)` (`a, b ≥ 0`) whose stored direction is nearest to `q`
    /// (`|q|` componentwise): of the candidates of §5.3 ([`lattice::candidates`]), the one whose
    /// direction in the file has the largest dot product with `q`.
    fn nearest_lattice_point(&self, q: [f64; 3]) -> (i64, i64) {
        let n = self.lattice_n as i64;
        let candidates = lattice::candidates(self.lattice_n, q[0], q[1], q[2]);
        let mut best = candidates.as_slice()[0];
        let mut best_dot = f64::NEG_INFINITY;
        for &(ci, ck) in candidates.as_slice() {
            let Some(&entry) = self.lookup.get(((ck as i64 + n) * self.side + (ci as i64 + n)) as usize) else {
                continue;
            };
            let Some(w) = self.directions.get((entry & !LOOKUP_FLIP) as usize) else { continue };
            // The first-quadrant lattice point's direction: the stored one, or its antipode.
            let s = if entry & LOOKUP_FLIP != 0 { -1.0 } else { 1.0 };
            let dot = s * (w[0] as f64 * q[0] + w[1] as f64 * q[1] + w[2] as f64 * q[2]);
            if entry != LOOKUP_NONE && dot > best_dot {
                best_dot = dot;
                best = (ci, ck);
            }
        }
        (best.0 as i64, best.1 as i64)
    }

    /// Steps 1 and 2 for a ray whose origin is given relative to `origin` (the world's origin for
    /// world rays: the ray is moved to the centre here). Not inlined: in the walk's function its
    /// values would crowd the registers the walk needs.
    #[inline(never)]
    pub(crate) fn setup(&self, ray: &Ray, origin: [f64; 3]) -> Option<Setup> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.dir.map(f64::from);
        let oc: [f64; 3] = std::array::from_fn(|i| ray.org[i] as f64 - origin[i]);
        // Clip to the scene's box grown by the margin: rays from outside start where the scene
        // starts. (Every point of the box that is outside the bounding sphere holds no triangle;
        // the walk clamps it to the grid.) Along an axis the ray does not move, 1/d is infinite:
        // both ends of the slab then give −∞ and +∞ if the origin lies between them (no
        // constraint), the same infinity if it does not (an empty interval), and a NaN (`0·∞`,
        // ignored by `lower` and `higher`) if it lies on one: conservative.
        let mut t0 = ray.tmin as f64;
        let mut t1 = ray.tmax as f64;
        for k in 0..3 {
            let inv = 1.0 / d[k];
            let ta = (self.box_lo[k] - oc[k]) * inv;
            let tb = (self.box_hi[k] - oc[k]) * inv;
            t0 = higher(t0, lower(ta, tb));
            t1 = lower(t1, higher(ta, tb));
        }
        if !(t0 <= t1) {
            return None;
        }
        let (dir, sign) = self.select_direction(d)?;
        let m = self.rotations.get(dir)?;
        let o = mul(m, oc);
        let dc = mul(m, d);
        // Only a lying file can make the beam coordinate stand still or turn non-finite. (The sum
        // is finite only if every term is: a rotation keeps lengths, so a valid file cannot
        // overflow it.)
        let sum = o[0] + o[1] + o[2] + dc[0] + dc[1] + dc[2];
        if !(dc[2] * sign > 0.0) || !sum.is_finite() {
            return None;
        }
        let inv_step = self.levels_per_unit;
        let (oq, dq) = ((o[2] + self.radius) * inv_step, dc[2] * inv_step);
        Some(Setup { dir, o, d: dc, t0, t1, oq, dq, inv_dq: 1.0 / dq, up: dq > 0.0 })
    }
}

/// Lattices of up to this many segments per octahedron edge (`2·8² + 1 = 129` directions) read
/// their nearest lattice point from [`FINE`].
const FINE_MAX_N: usize = 8;

/// Squares of [`FINE`] per lattice segment, along each axis of the octahedron's face.
const FINE_CELLS: usize = 8;

/// Where the squares of the lattice of `N` segments start in [`FINE`].
const FINE_START: [usize; FINE_MAX_N + 1] = {
    let mut start = [0; FINE_MAX_N + 1];
    let mut n = 1;
    while n < FINE_MAX_N {
        start[n + 1] = start[n] + (FINE_CELLS * n) * (FINE_CELLS * n);
        n += 1;
    }
    start
};

/// For each lattice of `N ≤ FINE_MAX_N` segments, the `8N × 8N` squares of `1/8` of a segment
/// that cover `(u, v) ∈ [0, N]²` (row `⌊8v⌋`, column `⌊8u⌋`): the lattice point `(a, b)`
/// (`a, b ≥ 0`, `a + b ≤ N`) whose direction is nearest to that of the square's centre, the
/// centre `(u, v, N − u − v)` of the face (moved onto the rim `u + v = N` if it lies past it).
/// Computed by the compiler: directions are compared by `(p·q)² / |p|²`, which orders them as
/// the angle does (all in the first octant), without a square root.
static FINE: [[u8; 2]; fine_len()] = fine_table();

/// The lattice point [`FINE`] holds for `(u, v)` (`0 ≤ u, v ≤ N`) on the face of the lattice of
/// `1 ≤ N ≤ FINE_MAX_N` segments.
#[cfg(test)]
fn fine_lattice_point(n: usize, u: f64, v: f64) -> [u8; 2] {
    Fine::new(n as u32).expect("N ≤ FINE_MAX_N").point(u, v)
}

/// The part of [`FINE`] for one lattice.
#[derive(Clone, Copy, Debug)]
struct Fine {
    /// Where the lattice's squares start in [`FINE`].
    start: usize,
    /// Squares per side, `8N`.
    side: usize,
}

impl Fine {
    /// The table of the lattice of `n` segments, if it has one (`1 ≤ n ≤ FINE_MAX_N`).
    fn new(n: u32) -> Option<Fine> {
        let n = n as usize;
        (1..=FINE_MAX_N).contains(&n).then(|| Fine { start: FINE_START[n], side: FINE_CELLS * n })
    }

    /// The lattice point held for `(u, v)`, `0 ≤ u, v ≤ N`.
    #[inline(always)]
    fn point(&self, u: f64, v: f64) -> [u8; 2] {
        // Truncation is floor for these non-negative values; `as u32` saturates (a NaN gives 0).
        let cell = |w: f64| ((w * FINE_CELLS as f64) as u32 as usize).min(self.side - 1);
        FINE.get(self.start + cell(v) * self.side + cell(u)).copied().unwrap_or([0, 0])
    }
}

const fn fine_len() -> usize {
    FINE_START[FINE_MAX_N] + (FINE_CELLS * FINE_MAX_N) * (FINE_CELLS * FINE_MAX_N)
}

const fn fine_table() -> [[u8; 2]; fine_len()] {
    let mut table = [[0u8; 2]; fine_len()];
    let mut n = 1;
    while n <= FINE_MAX_N {
        let m = FINE_CELLS * n;
        let nf = n as f64;
        let mut row = 0;
        while row < m {
            let mut col = 0;
            while col < m {
                let mut u = (col as f64 + 0.5) / FINE_CELLS as f64;
                let mut v = (row as f64 + 0.5) / FINE_CELLS as f64;
                if u + v > nf {
                    let s = nf / (u + v);
                    u *= s;
                    v *= s;
                }
                let q = [u, v, (nf - u - v).max(0.0)];
                let (mut best, mut best_score) = ([0u8; 2], -1.0);
                let mut a = 0;
                while a <= n {
                    let mut b = 0;
                    while a + b <= n {
                        let p = [a as f64, b as f64, (n - a - b) as f64];
                        let dot = p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
                        let score = dot * dot / (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                        if score > best_score {
                            best_score = score;
                            best = [a as u8, b as u8];
                        }
                        b += 1;
                    }
                    a += 1;
                }
                table[FINE_START[n] + row * m + col] = best;
                col += 1;
            }
            row += 1;
        }
        n += 1;
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit direction of `p`.
    fn unit(p: [f64; 3]) -> [f64; 3] {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|c| c / l)
    }

    /// The angle between unit vectors.
    fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
        (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).clamp(-1.0, 1.0).acos()
    }

    /// [`FINE`]'s lattice point is the nearest one for the centre of its square, so for any
    /// direction `q` it is at most twice the angle from `q` to that centre farther than the
    /// nearest lattice point (triangle inequality), and it is the nearest for most directions.
    /// (Which direction a ray takes changes only how much of the field it reads, never its answer:
    /// the oracle suites check the answers.)
    #[test]
    fn the_fine_table_gives_a_lattice_point_about_as_near_as_the_nearest() {
        let mut bits = crate::test_rng::xorshift(0x2545_f491_4f6c_dd1d);
        let mut next = move || (bits() >> 11) as f64 / (1u64 << 53) as f64;
        for n in 1..=FINE_MAX_N {
            let nf = n as f64;
            let points: Vec<[usize; 2]> = (0..=n).flat_map(|a| (0..=n - a).map(move |b| [a, b])).collect();
            let dir = |[a, b]: [usize; 2]| unit([a as f64, b as f64, (n - a - b) as f64]);
            let mut same = 0;
            let samples = 20_000;
            for i in 0..samples {
                // Random directions in the first octant, and some on the rim (z = 0).
                let q = unit([next(), next(), if i % 10 == 0 { 0.0 } else { next() }]);
                let scale = nf / (q[0] + q[1] + q[2]);
                let (u, v) = ((q[0] * scale).min(nf), (q[1] * scale).min(nf));
                let [a, b] = fine_lattice_point(n, u, v).map(|c| c as usize);
                assert!(a + b <= n, "N = {n}: ({a}, {b}) is not a lattice point");
                let nearest = points.iter().map(|&p| angle(q, dir(p))).fold(f64::INFINITY, f64::min);
                let centre = {
                    let c = |w: f64| ((w * 8.0).floor().min(8.0 * nf - 1.0) + 0.5) / 8.0;
                    let (cu, cv) = (c(u), c(v));
                    let s = if cu + cv > nf { nf / (cu + cv) } else { 1.0 };
                    unit([cu * s, cv * s, (nf - (cu + cv) * s).max(0.0)])
                };
                let got = angle(q, dir([a, b]));
                assert!(got <= nearest + 2.0 * angle(q, centre) + 1e-12, "N = {n}, q = {q:?}: {got} against {nearest}");
                same += (got <= nearest + 1e-12) as usize;
            }
            // Measured: 89% for N = 1 (three directions, long boundaries), 94% from N = 2 on.
            assert!(same * 100 >= samples * 88, "N = {n}: the nearest for only {same} of {samples}");
        }
    }
}
