//! Geometry shared by the VLF baker, the runtime and the baselines: rays and hits
//! ([`ray`]), the watertight triangle test ([`triangle`]) and the leaf kernel that every
//! acceleration path tests triangles with ([`kernel`]), the octahedral direction lattice with
//! its constant-time lookup ([`lattice`]), the per-direction frames ([`frame`]), a pinhole camera
//! ([`camera`]) and the brute-force reference intersector ([`BruteForce`]).
//!
//! No I/O, no allocation on query paths, no dependency on the file format.

#![deny(missing_docs)]
// Only the vector twins of the triangle test (`simd`) hold `unsafe`.
#![deny(unsafe_code)]

pub mod camera;
pub mod frame;
pub mod kernel;
pub mod lattice;
pub mod ray;
pub mod simd;
pub mod triangle;

pub use camera::Camera;
pub use kernel::{Closest, Triangles};
pub use lattice::Lattice;
pub use ray::{Counter, Hit, Intersector, Ray, TraceStats};
pub use simd::{Avx2, Avx512, Baseline, Isa, Tri};
pub use triangle::{Candidate, T_LIMIT, TriHit, TriRay, is_degenerate};

/// The reference intersector: every triangle, every ray, in id order, with the same leaf kernel
/// as the accelerated paths. Slow on purpose; the baseline every fast path is tested against.
#[derive(Clone, Copy, Debug)]
pub struct BruteForce<'a> {
    /// The triangles; a hit's `prim` is an index into this slice.
    pub triangles: &'a [[[f32; 3]; 3]],
    /// The point the triangles' coordinates are relative to (world origin: zero).
    pub origin: [f64; 3],
}

impl<'a> BruteForce<'a> {
    /// Over triangles in world coordinates.
    pub fn new(triangles: &'a [[[f32; 3]; 3]]) -> Self {
        BruteForce { triangles, origin: [0.0; 3] }
    }

    /// Over triangles stored relative to `origin`, as a field stores them (`TriRay::relative`).
    pub fn relative(triangles: &'a [[[f32; 3]; 3]], origin: [f64; 3]) -> Self {
        BruteForce { triangles, origin }
    }

    /// Every id in order. (At most 2³² − 1 triangles, as in a field.)
    fn ids(&self) -> std::ops::Range<u32> {
        0..self.triangles.len() as u32
    }

    /// The closest hit, counting into `counter`.
    pub fn closest_hit_with(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.closest_from(ray, self.origin, counter)
    }

    /// The first hit in id order, counting into `counter`.
    pub fn any_hit_with(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.any_from(ray, self.origin, counter)
    }

    /// The closest hit of `ray` moved by `−origin` into the triangles' frame: `origin` is
    /// the field `self.origin` for a world ray, zero for a local one (already in that frame).
    fn closest_from(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        counter.ray();
        let mut best = Closest::new(ray.tmax);
        TriRay::relative(ray, origin).closest_in(Baseline, self.triangles, self.ids(), &mut best, counter);
        best.hit
    }

    /// The first hit in id order of `ray` moved by `−origin`, as [`Self::closest_from`].
    fn any_from(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        counter.ray();
        TriRay::relative(ray, origin).any_in(Baseline, self.triangles, self.ids(), counter)
    }

    /// The first `max_hits` of every hit on `[tmin, tmax]`, in order of `t` then triangle id
    /// (`usize::MAX` for all): the reference of the runtime's all-hits and hit-count queries.
    /// Nothing for an invalid ray.
    pub fn all_hits_with(&self, ray: &Ray, max_hits: usize, counter: &mut impl Counter) -> Vec<Hit> {
        if !ray.is_valid() {
            return Vec::new();
        }
        counter.ray();
        let mut hits = Vec::new();
        let mut tmax = ray.tmax;
        TriRay::relative(ray, self.origin).hits_in(self.triangles, self.ids(), &mut tmax, counter, |h, _| hits.push(h));
        hits.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
        hits.truncate(max_hits);
        hits
    }

    /// [`Self::all_hits_with`], counting nothing.
    pub fn all_hits(&self, ray: &Ray, max_hits: usize) -> Vec<Hit> {
        self.all_hits_with(ray, max_hits, &mut ())
    }
}

impl Intersector for BruteForce<'_> {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_with(ray, &mut ())
    }

    fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit_with(ray, &mut ()).is_some()
    }

    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.closest_hit_with(ray, work)
    }

    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.any_hit_with(ray, work)
    }

    fn origin(&self) -> [f64; 3] {
        self.origin
    }

    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.closest_from(ray, [0.0; 3], work)
    }

    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.any_from(ray, [0.0; 3], work)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays through the interior of the shared diagonal of a quad split into two triangles never
    /// slip through, from many origins. (The diagonal's endpoints are the quad's outer corners,
    /// where a ray rounded to f32 may legitimately pass just outside.)
    #[test]
    fn shared_edges_are_watertight() {
        let q = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let bf = BruteForce::new(&tris);
        let mut state = 0x2545f4914f6cdd1du64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut misses = 0;
        for i in 1..100_000 {
            // Points exactly on the diagonal x = y (exact in f32), from random origins above and below.
            let s = if i < 1000 { i as f32 / 1000.0 } else { rnd().clamp(1e-3, 1.0 - 1e-3) };
            let target = [s, s, 0.0];
            let org = [rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0, if i % 2 == 0 { 1.0 + rnd() } else { -1.0 - rnd() }];
            let dir = [target[0] - org[0], target[1] - org[1], target[2] - org[2]];
            if bf.closest_hit(&Ray::new(org, dir)).is_none() {
                misses += 1;
            }
        }
        assert_eq!(misses, 0);
    }
}
