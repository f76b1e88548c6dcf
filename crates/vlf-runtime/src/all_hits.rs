//! Every hit along a ray, and how many there are: the queries behind sensor simulation, visibility
//! counts and inside/outside tests (an odd number of crossings), which a closest hit cannot answer.
//!
//! Built on the walk every query shares (the leaves along the ray, front to back, each leaf's
//! refs filtered by their boxes as the closest-hit query filters them) and on the leaf kernel ([`TriRay::hits_in`], the watertight test), so a hit here
//! is the hit the brute force ([`vlf_geom::BruteForce::all_hits`]) finds on that triangle, bit for
//! bit. Two things differ from the closest-hit query:
//!
//! - **A triangle lies in several leaves** (it spans tiles and BSP slabs), so it is met more than
//!   once; it is reported once. Testing it again gives the same bits, so the list is kept sorted
//!   by `(t, prim)` and a hit already in it is found by binary search.
//! - **The search stops** only once the `max_hits` closest hits are known: when there are
//!   `max_hits` of them and the farthest lies within the part of the ray already walked (the
//!   closest-hit query's stopping rule, for the `k`-th hit). Until then, the `k`-th hit's `t` is
//!   the end of the interval still searched.
//!
//! Order: by `t`, then by triangle id, so the first hit is the closest-hit query's (which also
//! takes the smaller id of a tie).

// The view from its own module, not the crate root: `lib.rs` uses this module.
use crate::query::FieldView;
use vlf_format::TriangleRecord;
use vlf_geom::{Hit, Ray, TriRay, Triangles};

/// The field's TRIANGLES section as the kernel reads it.
struct Stored<'a>(&'a [TriangleRecord]);

impl Triangles for Stored<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<&[[f32; 3]; 3]> {
        Some(&self.0.get(id as usize)?.v)
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.0.len()
    }
}

/// The hits of a batch of rays, ray after ray: ray `i`'s hits are
/// `hits[offsets[i] as usize..offsets[i + 1] as usize]`, in order of `t` (the layout of Open3D's
/// `ray_splits` and of a CSR matrix).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HitLists {
    /// `rays + 1` offsets into `hits`, from 0 to `hits.len()`.
    pub offsets: Vec<u64>,
    /// Every ray's hits, one ray after the other.
    pub hits: Vec<Hit>,
}

impl HitLists {
    /// The hits of ray `i`, in order of `t`.
    ///
    /// # Panics
    /// If `i` is not below the number of rays.
    pub fn ray(&self, i: usize) -> &[Hit] {
        &self.hits[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// The number of rays.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether the batch has no rays.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Appends `other`'s rays after these (the parallel batch stitches its parts).
    #[cfg(feature = "rayon")]
    fn extend(&mut self, other: HitLists) {
        let base = self.hits.len() as u64;
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.offsets.extend(other.offsets.iter().skip(1).map(|o| o + base));
        self.hits.extend(other.hits);
    }
}

/// A batch of all-hits queries found more hits than the limit it was given
/// ([`FieldView::all_hits_batch_within`]); it stopped there and returned none of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyHits {
    /// The limit, in hits.
    pub limit: usize,
}

impl std::fmt::Display for TooManyHits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the rays have more than {} hits in all", self.limit)
    }
}

impl std::error::Error for TooManyHits {}

/// The hits a batch may still find, counted across the threads of a parallel batch; `None` for
/// a batch without a limit, which counts nothing (no shared counter touched per ray).
struct HitLimit(Option<(usize, std::sync::atomic::AtomicUsize)>);

impl HitLimit {
    const NONE: HitLimit = HitLimit(None);

    fn new(limit: usize) -> HitLimit {
        HitLimit(Some((limit, std::sync::atomic::AtomicUsize::new(0))))
    }

    /// Counts `n` more hits: `Err` once the batch's count passes the limit. (Hits are held in
    /// memory, 16 bytes each, so the count cannot reach `usize::MAX`.)
    fn take(&self, n: usize) -> Result<(), TooManyHits> {
        let Some((limit, found)) = &self.0 else { return Ok(()) };
        if n > 0 && found.fetch_add(n, std::sync::atomic::Ordering::Relaxed) + n > *limit {
            return Err(TooManyHits { limit: *limit });
        }
        Ok(())
    }
}

/// The order of the lists: `t` (a total order; hits are never NaN), then the triangle id.
#[inline]
fn order(a: &Hit, t: f32, prim: u32) -> std::cmp::Ordering {
    a.t.total_cmp(&t).then(a.prim.cmp(&prim))
}

/// The smallest f32 above `t` (`t` is finite: a hit's distance). `f32::next_up` needs Rust 1.86.
#[inline]
fn next_up(t: f32) -> f32 {
    if t == 0.0 {
        f32::from_bits(1)
    } else if t > 0.0 {
        f32::from_bits(t.to_bits() + 1)
    } else {
        f32::from_bits(t.to_bits() - 1)
    }
}

/// The rays-per-task of the parallel batches: large enough that a task's bookkeeping (a vector of
/// hits, stitched at the end) is small against its tracing.
#[cfg(feature = "rayon")]
const CHUNK: usize = 1024;

impl FieldView<'_> {
    /// The `max_hits` closest hits of `ray` on `[tmin, tmax]` into `hits` (cleared first), in
    /// order of `t` then triangle id, each triangle once: the first `max_hits` of what testing
    /// every triangle gives, sorted the same way. `usize::MAX` for every hit; nothing for an
    /// invalid ray or `max_hits = 0`.
    ///
    /// Allocates only to grow `hits`: reuse one vector for many rays.
    pub fn all_hits_into(&self, ray: &Ray, max_hits: usize, hits: &mut Vec<Hit>) {
        hits.clear();
        if max_hits == 0 || !ray.is_valid() {
            return;
        }
        let tri_ray = TriRay::relative(ray, self.origin());
        let triangles = Stored(self.reader.triangles);
        // The end of the interval still searched: the k-th hit's t once there are k hits.
        let mut limit = ray.tmax;
        self.for_each_leaf_filtered(ray, |passing, exit_t| {
            // The refs whose boxes meet the ray over the leaf, up to the k-th hit once known.
            let ids = passing(exit_t.min(limit as f64));
            tri_ray.hits_in(&triangles, ids, &mut limit, &mut (), |h, limit| {
                let Err(at) = hits.binary_search_by(|x| order(x, h.t, h.prim)) else { return };
                if at >= max_hits {
                    return;
                }
                hits.insert(at, h);
                if hits.len() > max_hits {
                    hits.pop();
                }
                if hits.len() == max_hits {
                    // Not the k-th hit's `t` itself: the kernel compares its f64 `t` with the
                    // bound, and a hit just past it in f64 can round to the same f32 `t` (and
                    // come first in the order by a smaller id). The next float keeps it.
                    *limit = next_up(hits[max_hits - 1].t).min(ray.tmax);
                }
            });
            // Every hit at or before `exit_t` has been found (the walk's invariant): done once the
            // k-th is among them.
            hits.len() == max_hits && (limit as f64) <= exit_t
        });
    }

    /// The `max_hits` closest hits of `ray` on `[tmin, tmax]`, in order of `t` then triangle id,
    /// each triangle once (`usize::MAX` for all of them): [`Self::all_hits_into`], into a new
    /// vector. The same hits, bit for bit, as testing every triangle with the watertight kernel.
    pub fn all_hits(&self, ray: &Ray, max_hits: usize) -> Vec<Hit> {
        let mut hits = Vec::new();
        self.all_hits_into(ray, max_hits, &mut hits);
        hits
    }

    /// The number of triangles `ray` hits on `[tmin, tmax]`, each counted once however many of
    /// the field's leaves hold it (0 for an invalid ray): the length of [`Self::all_hits`]
    /// without a maximum. Allocates a vector for the hits while counting;
    /// [`Self::hit_count_into`] reuses one.
    pub fn hit_count(&self, ray: &Ray) -> u32 {
        self.hit_count_into(ray, &mut Vec::new())
    }

    /// [`Self::hit_count`], with `scratch` holding the hits while they are counted: reuse one
    /// vector for many rays.
    pub fn hit_count_into(&self, ray: &Ray, scratch: &mut Vec<Hit>) -> u32 {
        self.all_hits_into(ray, usize::MAX, scratch);
        // A field holds fewer than 2³² triangles, each counted once.
        scratch.len() as u32
    }

    /// [`Self::all_hits`] of every ray of a batch on the calling thread, at most `max_hits` each.
    pub fn all_hits_batch(&self, rays: &[Ray], max_hits: usize) -> HitLists {
        self.batch_within(rays, max_hits, &HitLimit::NONE).expect("a batch without a limit never passes it")
    }

    /// [`Self::all_hits_batch`], stopped as soon as the batch has found more than `limit` hits in
    /// all: the bound a caller sets when it must not run out of memory, where every ray may hit
    /// every triangle (a batch of `n` rays can hold `n` times the field's triangles).
    pub fn all_hits_batch_within(&self, rays: &[Ray], max_hits: usize, limit: usize) -> Result<HitLists, TooManyHits> {
        self.batch_within(rays, max_hits, &HitLimit::new(limit))
    }

    /// The batch on the calling thread, the hits found counted against `limit` (which the
    /// parallel batch's parts share).
    fn batch_within(&self, rays: &[Ray], max_hits: usize, limit: &HitLimit) -> Result<HitLists, TooManyHits> {
        let mut out = HitLists { offsets: Vec::with_capacity(rays.len() + 1), hits: Vec::new() };
        out.offsets.push(0);
        let mut scratch = Vec::new();
        for ray in rays {
            self.all_hits_into(ray, max_hits, &mut scratch);
            limit.take(scratch.len())?;
            out.hits.extend_from_slice(&scratch);
            out.offsets.push(out.hits.len() as u64);
        }
        Ok(out)
    }

    /// Hit counts of a batch on the calling thread: `out[i]` is [`Self::hit_count`] of `rays[i]`.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn hit_counts(&self, rays: &[Ray], out: &mut [u32]) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        let mut scratch = Vec::new();
        for (r, o) in rays.iter().zip(out) {
            *o = self.hit_count_into(r, &mut scratch);
        }
    }

    /// [`Self::all_hits_batch`] on all cores (rayon's global pool, or the pool installed around
    /// the call). The same lists, in the same order.
    #[cfg(feature = "rayon")]
    pub fn par_all_hits_batch(&self, rays: &[Ray], max_hits: usize) -> HitLists {
        self.par_batch_within(rays, max_hits, &HitLimit::NONE).expect("a batch without a limit never passes it")
    }

    /// [`Self::all_hits_batch_within`] on all cores: every thread stops once the batch's hits in
    /// all pass `limit`. The same lists, in the same order, when they do not.
    #[cfg(feature = "rayon")]
    pub fn par_all_hits_batch_within(
        &self,
        rays: &[Ray],
        max_hits: usize,
        limit: usize,
    ) -> Result<HitLists, TooManyHits> {
        self.par_batch_within(rays, max_hits, &HitLimit::new(limit))
    }

    #[cfg(feature = "rayon")]
    fn par_batch_within(&self, rays: &[Ray], max_hits: usize, limit: &HitLimit) -> Result<HitLists, TooManyHits> {
        use rayon::prelude::*;
        let parts: Vec<HitLists> =
            rays.par_chunks(CHUNK).map(|chunk| self.batch_within(chunk, max_hits, limit)).collect::<Result<_, _>>()?;
        let total = parts.iter().map(|p| p.hits.len()).sum();
        let mut out = HitLists { offsets: Vec::with_capacity(rays.len() + 1), hits: Vec::with_capacity(total) };
        out.offsets.push(0);
        for part in parts {
            out.extend(part);
        }
        Ok(out)
    }

    /// [`Self::hit_counts`] on all cores. The same counts, in the same order.
    ///
    /// # Panics
    /// If the slices differ in length.
    #[cfg(feature = "rayon")]
    pub fn par_hit_counts(&self, rays: &[Ray], out: &mut [u32]) {
        use rayon::prelude::*;
        assert_eq!(rays.len(), out.len(), "one output per ray");
        rays.par_chunks(CHUNK).zip(out.par_chunks_mut(CHUNK)).for_each(|(r, o)| self.hit_counts(r, o));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, prim: u32) -> Hit {
        Hit { t, prim, u: 0.0, v: 0.0 }
    }

    #[test]
    #[cfg(feature = "rayon")]
    fn lists_stitch_and_index_by_ray() {
        let mut a = HitLists { offsets: vec![0, 1, 1], hits: vec![hit(1.0, 3)] };
        a.extend(HitLists { offsets: vec![0, 2], hits: vec![hit(0.5, 1), hit(2.0, 0)] });
        assert_eq!(a.offsets, [0, 1, 1, 3]);
        assert_eq!(a.len(), 3);
        assert_eq!(a.ray(1), &[]);
        assert_eq!(a.ray(2), &[hit(0.5, 1), hit(2.0, 0)]);
        let mut empty = HitLists::default();
        assert!(empty.is_empty());
        empty.extend(HitLists { offsets: vec![0], hits: vec![] });
        assert_eq!(empty.offsets, [0]);
    }

    #[test]
    fn next_up_is_the_next_float() {
        for t in [0.0f32, -0.0, 1.0, -1.0, 3.5e-30, -7.25e12, f32::MAX / 2.0] {
            let up = next_up(t);
            assert!(up > t && f64::from(up) - f64::from(t) <= f64::from(t.abs()) * 2.0f64.powi(-23) + 1e-44, "{t}");
        }
        assert_eq!(next_up(1.0), 1.0 + f32::EPSILON);
        assert_eq!(next_up(-1.0), -1.0 + f32::EPSILON / 2.0);
    }

    #[test]
    fn order_is_t_then_id() {
        let list = [hit(-1.0, 9), hit(0.0, 2), hit(0.0, 5), hit(3.0, 0)];
        assert_eq!(list.binary_search_by(|x| order(x, 0.0, 5)), Ok(2));
        assert_eq!(list.binary_search_by(|x| order(x, 0.0, 3)), Err(2));
        assert_eq!(list.binary_search_by(|x| order(x, 4.0, 0)), Err(4));
    }
}
