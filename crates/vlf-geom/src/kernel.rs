//! The leaf kernel: test a list of triangles against one ray and keep the closest hit (or stop at
//! the first), counting the tests. Every acceleration path ends here: the field's leaves, the
//! kd-tree's leaves and the brute-force reference (all triangles, in id order) differ only in
//! which ids they hand to it and in what order, so they answer with the same bits.
//!
//! This is the plain scalar kernel, the reference twin of any faster one: a faster kernel must give
//! the same answer as a sequence of [`TriRay::closest_in`] calls over the same ids in the same order.
//! [`TriRay::hits_in`] hands every hit to the caller, for the queries that want them all.

use crate::ray::{Counter, Hit};
use crate::triangle::{TriHit, TriRay};

/// Where the kernel finds a triangle's vertices by id.
pub trait Triangles {
    /// The vertices of triangle `id`, or `None` if there is no such triangle (an id read from a
    /// file that lies; the kernel skips it).
    fn vertices(&self, id: u32) -> Option<[[f32; 3]; 3]>;

    /// The number of triangles: the ids `0..count()` are the valid ones.
    fn count(&self) -> usize;
}

impl Triangles for [[[f32; 3]; 3]] {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<[[f32; 3]; 3]> {
        self.get(id as usize).copied()
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.len()
    }
}

/// The closest hit found so far along one ray: the kernel's state from one leaf to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// The best hit, if any.
    pub hit: Option<Hit>,
    /// The end of the interval still searched: the ray's `tmax`, then the best hit's `t`.
    pub tmax: f32,
}

impl Closest {
    /// Nothing found yet on an interval that ends at `tmax`.
    #[inline(always)]
    pub fn new(tmax: f32) -> Self {
        Closest { hit: None, tmax }
    }
}

/// The next id of `ids` that `tris` holds, with its vertices.
#[inline(always)]
fn next_triangle<T: Triangles + ?Sized>(tris: &T, ids: &mut impl Iterator<Item = u32>) -> Option<(u32, [[f32; 3]; 3])> {
    loop {
        let id = ids.next()?;
        if let Some(v) = tris.vertices(id) {
            return Some((id, v));
        }
    }
}

impl Closest {
    /// Takes `hit` on triangle `id` if it lies within the interval still searched.
    #[inline(always)]
    fn take(&mut self, id: u32, hit: Option<TriHit>) {
        if let Some(h) = hit {
            self.tmax = h.t;
            self.hit = Some(Hit { t: h.t, prim: id, u: h.u, v: h.v });
        }
    }
}

impl TriRay {
    /// Tests the triangles `ids` of `tris` in order, keeping the closest hit in `best` (a hit at
    /// the same `t` as the best replaces it: the last one tested wins). Ids `tris` does not hold
    /// are skipped. Counts one test per triangle tested.
    ///
    /// Triangles are tested two at a time (SSE2 on x86-64) and their answers taken in
    /// order, each against the interval left by the one before: the answer of
    /// [`TriRay::closest_in_scalar`], its plain twin, to the bit.
    #[inline(always)]
    pub fn closest_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        best: &mut Closest,
        counter: &mut C,
    ) {
        let mut ids = ids.into_iter();
        while let Some((a, va)) = next_triangle(tris, &mut ids) {
            counter.test();
            let Some((b, vb)) = next_triangle(tris, &mut ids) else {
                best.take(a, self.candidate(&va).and_then(|c| c.within(self.tmin, best.tmax)));
                return;
            };
            counter.test();
            let [ca, cb] = self.candidates(&va, &vb);
            best.take(a, ca.and_then(|c| c.within(self.tmin, best.tmax)));
            best.take(b, cb.and_then(|c| c.within(self.tmin, best.tmax)));
        }
    }

    /// [`TriRay::closest_in`] one triangle at a time: the plain twin the tests hold it to.
    pub fn closest_in_scalar<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        best: &mut Closest,
        counter: &mut C,
    ) {
        for id in ids {
            let Some([a, b, c]) = tris.vertices(id) else { continue };
            counter.test();
            best.take(id, self.intersect(a, b, c, best.tmax));
        }
    }

    /// Tests the triangles `ids` of `tris` in order and returns the first hit on
    /// `[tmin, tmax]` (not necessarily the closest). Ids `tris` does not hold are skipped. Counts
    /// one test per triangle tested. Two at a time, as [`TriRay::closest_in`], with the answer and
    /// the count of [`TriRay::any_in_scalar`] (the second of a pair whose first is hit is not
    /// counted: the scalar kernel would not have tested it).
    #[inline(always)]
    pub fn any_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        tmax: f32,
        counter: &mut C,
    ) -> Option<Hit> {
        let hit = |id: u32, h: TriHit| Hit { t: h.t, prim: id, u: h.u, v: h.v };
        let mut ids = ids.into_iter();
        while let Some((a, va)) = next_triangle(tris, &mut ids) {
            counter.test();
            let Some((b, vb)) = next_triangle(tris, &mut ids) else {
                return self.candidate(&va).and_then(|c| c.within(self.tmin, tmax)).map(|h| hit(a, h));
            };
            let [ca, cb] = self.candidates(&va, &vb);
            if let Some(h) = ca.and_then(|c| c.within(self.tmin, tmax)) {
                return Some(hit(a, h));
            }
            counter.test();
            if let Some(h) = cb.and_then(|c| c.within(self.tmin, tmax)) {
                return Some(hit(b, h));
            }
        }
        None
    }

    /// [`TriRay::any_in`] one triangle at a time: the plain twin the tests hold it to.
    pub fn any_in_scalar<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        tmax: f32,
        counter: &mut C,
    ) -> Option<Hit> {
        for id in ids {
            let Some([a, b, c]) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(h) = self.intersect(a, b, c, tmax) {
                return Some(Hit { t: h.t, prim: id, u: h.u, v: h.v });
            }
        }
        None
    }

    /// Tests the triangles `ids` of `tris` in order and hands every hit on `[tmin, *tmax]` to
    /// `found`, which may shorten `*tmax` (the all-hits queries do, once they hold as many hits as
    /// were asked for). Ids `tris` does not hold are skipped. Counts one test per triangle tested.
    #[inline(always)]
    pub fn hits_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        tmax: &mut f32,
        counter: &mut C,
        mut found: impl FnMut(Hit, &mut f32),
    ) {
        for id in ids {
            let Some([a, b, c]) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(h) = self.intersect(a, b, c, *tmax) {
                found(Hit { t: h.t, prim: id, u: h.u, v: h.v }, tmax);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::Candidate;
    use crate::{Ray, TraceStats};

    const TRIS: [[[f32; 3]; 3]; 3] = [
        [[-1.0, -1.0, 2.0], [1.0, -1.0, 2.0], [0.0, 1.0, 2.0]],
        [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]],
        [[5.0, 5.0, 0.5], [6.0, 5.0, 0.5], [5.0, 6.0, 0.5]],
    ];

    /// A small deterministic generator (xorshift), so the tests need no dependency.
    fn rng(seed: u64) -> impl FnMut() -> u64 {
        let mut s = seed | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        }
    }

    /// Triangles of a small mesh that rays hit often, on edges, at equal `t` and behind one
    /// another: a grid of vertices shared by neighbours (some snapped to a coarse lattice, so that
    /// rays through lattice points meet shared edges and vertices exactly), some slivers and
    /// zero-area triangles, copies at the same place, and vertices a lying file could hold (NaN,
    /// infinities, huge values).
    fn awkward_triangles(next: &mut impl FnMut() -> u64) -> Vec<[[f32; 3]; 3]> {
        let mut unit = || (next() >> 40) as f32 / (1u64 << 24) as f32;
        let mut tris = Vec::new();
        let grid: Vec<[f32; 3]> = (0..25)
            .map(|i| [(i % 5) as f32 * 0.5 - 1.0, (i / 5) as f32 * 0.5 - 1.0, (unit() * 4.0).round() * 0.25])
            .collect();
        for i in 0..4 {
            for j in 0..4 {
                let v = |a: usize, b: usize| grid[(j + b) * 5 + i + a];
                tris.push([v(0, 0), v(1, 0), v(1, 1)]);
                tris.push([v(0, 0), v(1, 1), v(0, 1)]);
            }
        }
        for _ in 0..24 {
            let mut p = || [unit() * 2.0 - 1.0, unit() * 2.0 - 1.0, unit() * 2.0 - 1.0];
            let (a, b) = (p(), p());
            let c = match tris.len() % 4 {
                0 => [a[0] + 1e-5, a[1] - 1e-5, a[2] + 1e-5], // sliver
                1 => a,                                       // zero area
                _ => p(),
            };
            tris.push([a, b, c]);
        }
        let copy = tris[3];
        tris.push(copy);
        let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3e38, -0.0];
        for k in 0..odd.len() {
            let mut t = tris[k * 3];
            t[k % 3][k % 3] = odd[k];
            tris.push(t);
        }
        tris
    }

    /// The two-lane kernel gives the scalar kernel's answers and counts, to the bit: the
    /// candidates of each pair, the closest hit and the first hit, over rays through lattice
    /// points (shared edges and vertices), along the axes (shear by zero), and random ones, with
    /// lists that repeat ids and name ids that do not exist, of every length (odd ones end in a
    /// single triangle), and finite and infinite `tmax`.
    #[test]
    fn the_two_lane_kernel_is_the_scalar_kernel() {
        let mut next = rng(0x51f1);
        let tris = awkward_triangles(&mut next);
        let n = tris.len() as u64;
        let mut unit = {
            let mut next = rng(0x77);
            move || (next() >> 40) as f32 / (1u64 << 24) as f32
        };
        for round in 0..20_000 {
            let org = [unit() * 4.0 - 2.0, unit() * 4.0 - 2.0, unit() * 4.0 - 2.0];
            let target = match round % 3 {
                // A lattice point of the grid: on shared edges and vertices.
                0 => [
                    ((unit() * 8.0).round() * 0.25 - 1.0),
                    ((unit() * 8.0).round() * 0.25 - 1.0),
                    0.25 * (unit() * 4.0).round(),
                ],
                1 => [org[0], org[1], org[2] + if unit() < 0.5 { 1.0 } else { -1.0 }],
                _ => [unit() * 2.0 - 1.0, unit() * 2.0 - 1.0, unit() * 2.0 - 1.0],
            };
            let dir = [target[0] - org[0], target[1] - org[1], target[2] - org[2]];
            let mut ray = Ray::new(org, dir);
            ray.tmin = if round % 5 == 0 { 0.5 } else { 0.0 };
            ray.tmax = if round % 2 == 0 { f32::INFINITY } else { 0.5 + unit() * 2.0 };
            if !ray.is_valid() {
                continue;
            }
            let tr = TriRay::new(&ray);
            for (p, q) in [(next() % n, next() % n), (next() % n, next() % n)] {
                let (p, q) = (&tris[p as usize], &tris[q as usize]);
                let want = [tr.candidate(p), tr.candidate(q)];
                let got = tr.candidates(p, q);
                let bits = |c: [Option<Candidate>; 2]| c.map(|c| c.map(|c| [c.t, c.u, c.v].map(f64::to_bits)));
                assert_eq!(bits(got), bits(want), "round {round}");
            }
            let len = (next() % 40) as usize;
            // Ids past the end stand for the ids a lying file names (skipped).
            let ids: Vec<u32> = (0..len).map(|_| (next() % (n + 3)) as u32).collect();
            let (mut fast, mut plain) = (TraceStats::default(), TraceStats::default());
            let (mut a, mut b) = (Closest::new(ray.tmax), Closest::new(ray.tmax));
            tr.closest_in(&tris[..], ids.iter().copied(), &mut a, &mut fast);
            tr.closest_in_scalar(&tris[..], ids.iter().copied(), &mut b, &mut plain);
            let hit_bits = |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
            assert_eq!(
                (hit_bits(a.hit), a.tmax.to_bits()),
                (hit_bits(b.hit), b.tmax.to_bits()),
                "round {round}: {ids:?}"
            );
            assert_eq!(fast, plain);
            let got = tr.any_in(&tris[..], ids.iter().copied(), ray.tmax, &mut fast);
            let want = tr.any_in_scalar(&tris[..], ids.iter().copied(), ray.tmax, &mut plain);
            assert_eq!(hit_bits(got), hit_bits(want), "round {round}: {ids:?}");
            assert_eq!(fast, plain, "round {round}: any-hit counts");
        }
    }

    #[test]
    fn closest_keeps_the_nearest_and_counts_every_test() {
        let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let tr = TriRay::new(&ray);
        let mut best = Closest::new(ray.tmax);
        let mut work = TraceStats::default();
        // A lying id (7) is skipped and not counted.
        tr.closest_in(&TRIS[..], [0, 7, 1, 2], &mut best, &mut work);
        let hit = best.hit.unwrap();
        assert_eq!((hit.prim, hit.t, best.tmax), (1, 1.0, 1.0));
        assert_eq!(work.triangle_tests, 3);
        // A later leaf with only farther triangles changes nothing.
        tr.closest_in(&TRIS[..], [0], &mut best, &mut work);
        assert_eq!(best.hit.unwrap().prim, 1);
    }

    #[test]
    fn any_stops_at_the_first_hit_within_tmax() {
        let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let tr = TriRay::new(&ray);
        let mut work = TraceStats::default();
        assert_eq!(tr.any_in(&TRIS[..], [2, 0, 1], f32::INFINITY, &mut work).unwrap().prim, 0);
        assert_eq!(work.triangle_tests, 2);
        assert_eq!(tr.any_in(&TRIS[..], [0, 1], 0.5, &mut ()), None);
    }

    #[test]
    fn hits_in_reports_every_hit_within_a_shrinking_tmax() {
        let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let tr = TriRay::new(&ray);
        let mut work = TraceStats::default();
        let mut seen = Vec::new();
        let mut tmax = f32::INFINITY;
        tr.hits_in(&TRIS[..], [0, 7, 2, 1], &mut tmax, &mut work, |h, _| seen.push((h.prim, h.t)));
        assert_eq!(seen, [(0, 2.0), (1, 1.0)]);
        assert_eq!(work.triangle_tests, 3);
        // The callback shortens the interval: triangle 0 (t = 2) is then out of it.
        let mut ids = Vec::new();
        tr.hits_in(&TRIS[..], [1, 0], &mut tmax, &mut (), |h, tmax| {
            ids.push(h.prim);
            *tmax = h.t;
        });
        assert_eq!((ids, tmax), (vec![1], 1.0));
    }
}
