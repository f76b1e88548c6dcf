//! The leaf kernel: test a list of triangles against one ray and keep the closest hit (or stop at
//! the first), counting the tests. Every acceleration path ends here: the field's leaves, the
//! kd-tree's leaves and the brute-force reference (all triangles, in id order) differ only in
//! which ids they hand to it and in what order, so they answer with the same bits.
//!
//! This is the plain scalar kernel, the reference twin of any faster one: a faster kernel must give
//! the same answer as a sequence of [`TriRay::closest_in`] calls over the same ids in the same order.
//! [`TriRay::hits_in`] hands every hit to the caller, for the queries that want them all.

use crate::ray::{Counter, Hit};
use crate::simd::{Isa, Tri};
use crate::triangle::{Candidate, TriRay};

/// Where the kernel finds a triangle's vertices by id.
pub trait Triangles {
    /// The vertices of triangle `id`, or `None` if there is no such triangle (an id read from a
    /// file that lies, or one a caller hides; the kernel skips it).
    fn vertices(&self, id: u32) -> Option<&Tri>;

    /// The number of triangles: the ids `0..count()` are the valid ones.
    fn count(&self) -> usize;
}

impl Triangles for [Tri] {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<&Tri> {
        self.get(id as usize)
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.len()
    }
}

/// The closest hit found so far along one ray: the kernel's state from one leaf to the next.
///
/// The answer does not depend on the order in which triangles are tested: of the hits on the
/// ray's range, it is the one with the smallest `t` (rounded to f32), and of several at the same
/// `t`, the one with the smallest id. So every acceleration path, whatever order it meets
/// triangles in, and the brute force give the same hit, bit for bit.
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

    /// Takes the place `c` where the line of `ray` meets triangle `id`, if it lies on the ray's
    /// range `[tmin, tmax]` (compared in f64, before rounding) and comes before the best hit (its
    /// `t` rounded to f32 smaller, or equal with a smaller id).
    #[inline(always)]
    pub fn take(&mut self, ray: &TriRay, id: u32, c: Candidate) {
        if !(c.t >= ray.tmin && c.t <= ray.tmax) {
            return;
        }
        let t = c.t as f32;
        if t < self.tmax || (t == self.tmax && self.hit.is_none_or(|h| id < h.prim)) {
            self.tmax = t;
            self.hit = Some(Hit { t, prim: id, u: c.u as f32, v: c.v as f32 });
        }
    }
}

/// A triangle the kernel never hits, to fill the lanes of a last, short batch.
pub static FILLER: Tri = [[0.0; 3]; 3];

/// The next triangles of `ids` that `tris` holds, up to four: their ids and vertices, and how
/// many there are (the unused lanes hold [`FILLER`]).
#[inline(always)]
fn next_four<'t, T: Triangles + ?Sized>(
    tris: &'t T,
    ids: &mut impl Iterator<Item = u32>,
) -> ([u32; 4], [&'t Tri; 4], usize) {
    let mut id = [0u32; 4];
    let mut tri = [&FILLER; 4];
    let mut n = 0;
    while n < 4 {
        let Some(i) = ids.next() else { break };
        if let Some(t) = tris.vertices(i) {
            (id[n], tri[n]) = (i, t);
            n += 1;
        }
    }
    (id, tri, n)
}

impl TriRay {
    /// Tests the first `n ≤ 4` of `tris` (triangles `ids`; the other lanes are ignored), keeping
    /// the closest hit in `best` ([`Closest::take`]). The four-lane test of `isa`: the answer of
    /// [`TriRay::closest_in_scalar`] over the same triangles, to the bit.
    #[inline(always)]
    pub fn closest4(&self, isa: impl Isa, ids: [u32; 4], tris: [&Tri; 4], n: usize, best: &mut Closest) {
        let found = isa.candidates_first(self, tris, n);
        for i in 0..n.min(4) {
            if let Some(c) = found[i] {
                best.take(self, ids[i], c);
            }
        }
    }

    /// Tests the first `n ≤ 4` of `tris` (triangles `ids`) and returns the first of them, in
    /// order, that the ray hits on its range, with its lane: the four-lane twin of
    /// [`TriRay::any_in_scalar`].
    #[inline(always)]
    pub fn any4(&self, isa: impl Isa, ids: [u32; 4], tris: [&Tri; 4], n: usize) -> Option<(usize, Hit)> {
        let found = isa.candidates_first(self, tris, n);
        (0..n.min(4)).find_map(|i| Some((i, self.hit_on(ids[i], found[i]?)?)))
    }

    /// Tests the triangles `ids` of `tris`, keeping the closest hit in `best` ([`Closest::take`]:
    /// the answer does not depend on their order). Ids `tris` does not hold are skipped. Counts
    /// one test per triangle tested.
    ///
    /// Triangles are tested four at a time with the vector test of `isa` ([`crate::simd`]): the
    /// answer of [`TriRay::closest_in_scalar`], its plain twin, to the bit.
    #[inline(always)]
    pub fn closest_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        isa: impl Isa,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        best: &mut Closest,
        counter: &mut C,
    ) {
        let mut ids = ids.into_iter();
        loop {
            let (id, tri, n) = next_four(tris, &mut ids);
            if n == 0 {
                return;
            }
            for _ in 0..n {
                counter.test();
            }
            self.closest4(isa, id, tri, n, best);
            if n < 4 {
                return;
            }
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
            let Some(tri) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(c) = self.candidate(tri) {
                best.take(self, id, c);
            }
        }
    }

    /// Tests the triangles `ids` of `tris` in order and returns the first hit on
    /// `[tmin, tmax]` (not necessarily the closest). Ids `tris` does not hold are skipped. Counts
    /// one test per triangle tested, up to the one hit. Four at a time, as
    /// [`TriRay::closest_in`], with the answer and the count of [`TriRay::any_in_scalar`].
    #[inline(always)]
    pub fn any_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        isa: impl Isa,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        counter: &mut C,
    ) -> Option<Hit> {
        let mut ids = ids.into_iter();
        loop {
            let (id, tri, n) = next_four(tris, &mut ids);
            if n == 0 {
                return None;
            }
            let found = self.any4(isa, id, tri, n);
            for _ in 0..found.map_or(n, |(i, _)| i + 1) {
                counter.test();
            }
            if let Some((_, hit)) = found {
                return Some(hit);
            }
            if n < 4 {
                return None;
            }
        }
    }

    /// [`TriRay::any_in`] one triangle at a time: the plain twin the tests hold it to.
    pub fn any_in_scalar<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        counter: &mut C,
    ) -> Option<Hit> {
        for id in ids {
            let Some(tri) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(hit) = self.candidate(tri).and_then(|c| self.hit_on(id, c)) {
                return Some(hit);
            }
        }
        None
    }

    /// The hit on triangle `id` where the ray's line meets it at `c`, if that lies on the ray's
    /// range.
    #[inline(always)]
    fn hit_on(&self, id: u32, c: Candidate) -> Option<Hit> {
        let h = c.within(self.tmin, self.tmax)?;
        Some(Hit { t: h.t, prim: id, u: h.u, v: h.v })
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
            let Some(tri) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(h) = self.candidate(tri).and_then(|c| c.within(self.tmin, (*tmax as f64).min(self.tmax))) {
                found(Hit { t: h.t, prim: id, u: h.u, v: h.v }, tmax);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::Baseline;
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

    /// Every vector kernel gives the scalar kernel's answers and counts, to the bit: the
    /// candidates of each pair and each four (two-lane SSE2, the baseline's four, and AVX2's four
    /// where the CPU has it), the closest hit and the first hit, over rays through lattice points
    /// (shared edges and vertices), along the axes (shear by zero), and random ones, with lists
    /// that repeat ids and name ids that do not exist, of every length (short last batches), and
    /// finite and infinite `tmax`. The closest hit is also the same for the list reversed: it
    /// does not depend on the order of the tests.
    #[test]
    fn the_vector_kernels_are_the_scalar_kernel() {
        let avx2 = crate::simd::Avx2::detect();
        println!("AVX2 on this CPU: {}", avx2.is_some());
        let mut next = rng(0x51f1);
        let tris = awkward_triangles(&mut next);
        let n = tris.len() as u64;
        let mut unit = {
            let mut next = rng(0x77);
            move || (next() >> 40) as f32 / (1u64 << 24) as f32
        };
        let bits = |c: Option<Candidate>| c.map(|c| [c.t, c.u, c.v].map(f64::to_bits));
        let hit_bits = |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
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
            let four: [&Tri; 4] = std::array::from_fn(|_| &tris[(next() % n) as usize]);
            let want = four.map(|t| bits(tr.candidate(t)));
            let [a, b] = crate::simd::candidates2(&tr, four[0], four[1]);
            assert_eq!([bits(a), bits(b)], [want[0], want[1]], "round {round}: two lanes");
            assert_eq!(crate::simd::Baseline.candidates4(&tr, four).map(bits), want, "round {round}: baseline");
            if let Some(avx2) = avx2 {
                assert_eq!(avx2.candidates4(&tr, four).map(bits), want, "round {round}: AVX2");
            }
            let len = (next() % 40) as usize;
            // Ids past the end stand for the ids a lying file names (skipped).
            let ids: Vec<u32> = (0..len).map(|_| (next() % (n + 3)) as u32).collect();
            let (mut plain_work, mut plain) = (TraceStats::default(), Closest::new(ray.tmax));
            tr.closest_in_scalar(&tris[..], ids.iter().copied(), &mut plain, &mut plain_work);
            let mut reversed = Closest::new(ray.tmax);
            tr.closest_in_scalar(&tris[..], ids.iter().rev().copied(), &mut reversed, &mut ());
            assert_eq!(hit_bits(reversed.hit), hit_bits(plain.hit), "round {round}: order matters");
            let any_work = &mut TraceStats::default();
            let any_plain = tr.any_in_scalar(&tris[..], ids.iter().copied(), any_work);
            let check = |isa: &dyn Fn(&mut Closest, &mut TraceStats) -> Option<Hit>, name: &str| {
                let (mut work, mut best) = (TraceStats::default(), Closest::new(ray.tmax));
                let any = isa(&mut best, &mut work);
                assert_eq!(
                    (hit_bits(best.hit), best.tmax.to_bits()),
                    (hit_bits(plain.hit), plain.tmax.to_bits()),
                    "round {round} {name}: {ids:?}"
                );
                assert_eq!(hit_bits(any), hit_bits(any_plain), "round {round} {name}: any hit of {ids:?}");
                work
            };
            let base = check(
                &|best, work| {
                    tr.closest_in(crate::simd::Baseline, &tris[..], ids.iter().copied(), best, work);
                    let mut any_work = TraceStats::default();
                    let any = tr.any_in(crate::simd::Baseline, &tris[..], ids.iter().copied(), &mut any_work);
                    work.add(&any_work);
                    any
                },
                "baseline",
            );
            let mut want_work = plain_work;
            want_work.add(any_work);
            assert_eq!(base, want_work, "round {round}: counts");
            if let Some(avx2) = avx2 {
                let wide = check(
                    &|best, work| {
                        tr.closest_in(avx2, &tris[..], ids.iter().copied(), best, work);
                        let mut any_work = TraceStats::default();
                        let any = tr.any_in(avx2, &tris[..], ids.iter().copied(), &mut any_work);
                        work.add(&any_work);
                        any
                    },
                    "AVX2",
                );
                assert_eq!(wide, want_work, "round {round}: AVX2 counts");
            }
        }
    }

    #[test]
    fn closest_keeps_the_nearest_and_counts_every_test() {
        let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let tr = TriRay::new(&ray);
        let mut best = Closest::new(ray.tmax);
        let mut work = TraceStats::default();
        // A lying id (7) is skipped and not counted.
        tr.closest_in(Baseline, &TRIS[..], [0, 7, 1, 2], &mut best, &mut work);
        let hit = best.hit.unwrap();
        assert_eq!((hit.prim, hit.t, best.tmax), (1, 1.0, 1.0));
        assert_eq!(work.triangle_tests, 3);
        // A later leaf with only farther triangles changes nothing.
        tr.closest_in(Baseline, &TRIS[..], [0], &mut best, &mut work);
        assert_eq!(best.hit.unwrap().prim, 1);
    }

    #[test]
    fn any_stops_at_the_first_hit_within_tmax() {
        let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
        let tr = TriRay::new(&ray);
        let mut work = TraceStats::default();
        assert_eq!(tr.any_in(Baseline, &TRIS[..], [2, 0, 1], &mut work).unwrap().prim, 0);
        assert_eq!(work.triangle_tests, 2);
        let short = TriRay::new(&Ray { tmax: 0.5, ..ray });
        assert_eq!(short.any_in(Baseline, &TRIS[..], [0, 1], &mut ()), None);
    }

    /// A hit whose `t` is past the largest finite f32 is no hit, on every path: before, a ray
    /// with a tiny direction met both triangles at `t = ∞` and the farther one (the lower id)
    /// won the tie.
    #[test]
    fn a_hit_past_the_largest_float_is_no_hit() {
        // Triangles 1 and 0 lie at z = 1 and z = 2: t = 1 / d and 2 / d.
        for (dz, want) in [(2e-39f32, None), (4e-39, Some(1)), (1.0, Some(1))] {
            let ray = Ray::new([0.0, 0.0, 0.0], [0.0, 0.0, dz]);
            assert!(ray.is_valid());
            let tr = TriRay::new(&ray);
            let mut best = Closest::new(ray.tmax);
            tr.closest_in(Baseline, &TRIS[..], [0, 1, 2], &mut best, &mut ());
            assert_eq!(best.hit.map(|h| h.prim), want, "closest, d = {dz:e}");
            assert!(best.tmax.is_finite() || want.is_none(), "d = {dz:e}: t = {}", best.tmax);
            let mut scalar = Closest::new(ray.tmax);
            tr.closest_in_scalar(&TRIS[..], [0, 1, 2], &mut scalar, &mut ());
            assert_eq!(scalar, best, "the scalar twin, d = {dz:e}");
            // Any hit finds triangle 0 first when it counts, so it must skip it past the limit.
            let any = tr.any_in(Baseline, &TRIS[..], [0, 1], &mut ()).map(|h| h.prim);
            assert_eq!(any.is_some(), want.is_some(), "any, d = {dz:e}");
            let mut all = Vec::new();
            let mut tmax = f32::INFINITY;
            tr.hits_in(&TRIS[..], [0, 1, 2], &mut tmax, &mut (), |h, _| all.push(h.prim));
            let expect: Vec<u32> = match want {
                None => vec![],
                Some(_) if dz < 1.0 => vec![1],
                Some(_) => vec![0, 1],
            };
            assert_eq!(all, expect, "all, d = {dz:e}");
            assert_eq!(tr.intersect(TRIS[0][0], TRIS[0][1], TRIS[0][2], f32::INFINITY).is_some(), dz == 1.0);
        }
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
