//! The leaf kernel: test a list of triangles against one ray and keep the closest hit (or stop at
//! the first), counting the tests. Every acceleration path ends here: the field's leaves, the
//! kd-tree's leaves and the brute-force reference (all triangles, in id order) differ only in
//! which ids they hand to it and in what order, so they answer with the same bits.
//!
//! This is the plain scalar kernel, the reference twin of any faster one: a faster kernel must give
//! the same answer as a sequence of [`TriRay::closest_in`] calls over the same ids in the same order.
//! [`TriRay::hits_in`] hands every hit to the caller, for the queries that want them all.

use crate::ray::{Counter, Hit};
use crate::triangle::TriRay;

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

impl TriRay {
    /// Tests the triangles `ids` of `tris` in order, keeping the closest hit in `best` (a hit at
    /// the same `t` as the best replaces it: the last one tested wins). Ids `tris` does not hold
    /// are skipped. Counts one test per triangle tested.
    #[inline(always)]
    pub fn closest_in<T: Triangles + ?Sized, C: Counter>(
        &self,
        tris: &T,
        ids: impl IntoIterator<Item = u32>,
        best: &mut Closest,
        counter: &mut C,
    ) {
        for id in ids {
            let Some([a, b, c]) = tris.vertices(id) else { continue };
            counter.test();
            if let Some(h) = self.intersect(a, b, c, best.tmax) {
                best.tmax = h.t;
                best.hit = Some(Hit { t: h.t, prim: id, u: h.u, v: h.v });
            }
        }
    }

    /// Tests the triangles `ids` of `tris` in order and returns the first hit on
    /// `[tmin, tmax]` (not necessarily the closest). Ids `tris` does not hold are skipped. Counts
    /// one test per triangle tested.
    #[inline(always)]
    pub fn any_in<T: Triangles + ?Sized, C: Counter>(
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
    use crate::{Ray, TraceStats};

    const TRIS: [[[f32; 3]; 3]; 3] = [
        [[-1.0, -1.0, 2.0], [1.0, -1.0, 2.0], [0.0, 1.0, 2.0]],
        [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]],
        [[5.0, 5.0, 0.5], [6.0, 5.0, 0.5], [5.0, 6.0, 0.5]],
    ];

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
