//! Batches of rays, interleaved to hide memory latency.
//!
//! A single ray's walk is a chain of dependent loads: the tile's TILES entry, then its block,
//! then a leaf's boxes and ids, then the triangles. When the field is larger than the caches,
//! most of those miss, and a ray spends most of its time waiting on them one after the other.
//! A batch keeps [`IN_FLIGHT`] rays going at once: it moves one ray a step along its walk
//! ([`Walk::step`]), which starts loading what that ray reads next, then turns to the next ray,
//! and comes back to the first when its data has had time to arrive (asynchronous memory access
//! chaining: Kocberber et al., "Asynchronous Memory Access Chaining", VLDB 2015). Each ray sees
//! the same leaves in the same order and runs the same leaf tests as a single closest-hit query,
//! so a batch gives the same answers, bit for bit, in the rays' order. An any-hit ray walks as in
//! the single query (`Setup::for_any_hit`).

use crate::filter::Passing;
use crate::prefetch::prefetch;
use crate::query::{FieldTriangles, FieldView, closest_in_refs, closest_refs};
use crate::walk::{Leaf, Setup, Step, Walk};
use vlf_geom::{Baseline, Closest, Hit, Ray, TriRay};

/// Rays a batch keeps in flight: enough to cover a miss to memory (150–200 ns on the machines
/// measured) with the steps of the others, few enough that their state stays in L1.
const IN_FLIGHT: usize = 8;

/// Fields whose tile blocks and triangles take fewer bytes than this mostly stay in the cache:
/// interleaving their rays only adds its bookkeeping. Measured (`examples/batch_choice.rs` on
/// 262,144 incoherent rays; `docs/benchmarks/where-the-time-goes.md`, 2026-12-06): on an Intel
/// Xeon VM fields of 12 to 58 MB traced them 9–42% slower interleaved than in turn, an 88 MB field
/// as fast (1.12× faster in a run whose misses cost more); on an AMD EPYC VM the bunny's (13 MB)
/// and a 10K scene's (16 MB) 30–35% slower, the 100K scenes' (84–95 MiB) 12–15% faster. It was
/// 8 MiB while automatic fields of small scenes were smaller than that.
const CACHED_BYTES: usize = 32 << 20;

/// Rays a batch judges at a time: traced in turn if they are coherent, else interleaved.
const WINDOW: usize = 256;

/// Neighbouring rays that start within this many tile widths of each other count as coherent,
/// whatever their directions. Measured (`docs/benchmarks/where-the-time-goes.md`): rays leaving
/// neighbouring pixels' hits in random directions (ambient occlusion, diffuse bounces) ran up to
/// 1.8× slower interleaved than in turn; shadow rays from every eighth pixel, whose origins lie
/// two tiles apart on a 128² grid, 1.4× slower; rays from origins spread over the scene,
/// 1.2–1.5× faster.
const NEAR_TILES: f64 = 4.0;

/// Whether a batch query interleaves its rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interleave {
    /// Interleave windows of rays that are not coherent, on a field larger than a cache holds;
    /// trace the others in turn. What the batch queries do.
    #[default]
    Auto,
    /// Interleave every window.
    Always,
    /// Trace every ray in turn, as a loop over the single-ray query would.
    Never,
}

/// One ray in flight: its walk, its search state `S`, and the leaf it will test next (loading).
struct Lane<'a, S> {
    index: usize,
    setup: Setup,
    walk: Walk<'a>,
    tri_ray: TriRay,
    state: S,
    pending: Pending<'a>,
    /// For an any-hit search that puts off the leaf where its walk starts
    /// (`Setup::for_any_hit`): whether the ray has reached no leaf yet, and that leaf, put off
    /// until its walk ends (as the single-ray query does: `crate::trace`'s `OriginLeaf`).
    undecided: bool,
    deferred: Option<Leaf<'a>>,
}

/// What a lane will do on its next turn, besides stepping its walk.
enum Pending<'a> {
    Nothing,
    /// Choose the refs of a leaf whose boxes and ids are loading, and ask for their triangles.
    Leaf(Leaf<'a>),
    /// Test the refs of a leaf the ray leaves at the given parameter (the triangles loading).
    Refs(Passing<'a>, f64),
}

impl<'a> FieldView<'a> {
    /// The closest hits of `rays` (world coordinates): `out[i]` is
    /// [`FieldView::closest_hit`]`(&rays[i])`, the same hit bit for bit. On a field larger than
    /// the cache, rays whose neighbours start far from them are traced several at once,
    /// interleaved, so that their cache misses overlap ([`Interleave::Auto`]); rays that start
    /// near each other, in any directions, one after the other. Allocates nothing.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn closest_hits(&self, rays: &[Ray], out: &mut [Option<Hit>]) {
        self.closest_hits_in(rays, out, Interleave::Auto);
    }

    /// [`FieldView::closest_hits`], interleaving as `how` says. The answers do not depend on it.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn closest_hits_in(&self, rays: &[Ray], out: &mut [Option<Hit>], how: Interleave) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        self.closest_hits_each(rays, how, |i, hit| out[i] = hit);
    }

    /// [`FieldView::closest_hits_in`], handing ray `i`'s hit to `out(i, hit)` (in no particular
    /// order).
    pub(crate) fn closest_hits_each(&self, rays: &[Ray], how: Interleave, mut out: impl FnMut(usize, Option<Hit>)) {
        let tris = FieldTriangles(self.reader.triangles);
        for (w, window) in rays.chunks(WINDOW).enumerate() {
            let base = w * WINDOW;
            if !self.worth_interleaving(window, how) {
                for (i, ray) in window.iter().enumerate() {
                    out(base + i, self.closest_hit(ray));
                }
                continue;
            }
            self.interleaved(
                window,
                false,
                |ray| Closest::new(ray.tmax),
                |best, leaf| closest_refs(leaf, best, &[]),
                |tri_ray, _, best, refs, exit_t| closest_in_refs(tri_ray, &tris, refs, exit_t, best, &mut ()),
                |i, best| out(base + i, best.and_then(|b| b.hit)),
            );
        }
    }

    /// Whether each of `rays` hits anything: `out[i]` is [`FieldView::any_hit`]`(&rays[i])`.
    /// Interleaved as [`FieldView::closest_hits`]; allocates nothing.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        self.any_hits_in(rays, out, Interleave::Auto);
    }

    /// [`FieldView::any_hits`], interleaving as `how` says. The answers do not depend on it.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn any_hits_in(&self, rays: &[Ray], out: &mut [bool], how: Interleave) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        let tris = FieldTriangles(self.reader.triangles);
        for (rays, out) in rays.chunks(WINDOW).zip(out.chunks_mut(WINDOW)) {
            if !self.worth_interleaving(rays, how) {
                for (ray, out) in rays.iter().zip(out.iter_mut()) {
                    *out = self.any_hit(ray);
                }
                continue;
            }
            self.interleaved(
                rays,
                true,
                |_| None,
                |_, leaf| leaf.passing(leaf.exit_t, &[]),
                |tri_ray, _, found, refs, _| {
                    *found = tri_ray.any_in(Baseline, &tris, refs, &mut ());
                    found.is_some()
                },
                |i, found| out[i] = found.flatten().is_some(),
            );
        }
    }

    /// Whether to interleave `rays`: as `how` says, and for [`Interleave::Auto`], whether it
    /// pays: the field is larger than a cache holds, and the rays are not coherent.
    fn worth_interleaving(&self, rays: &[Ray], how: Interleave) -> bool {
        match how {
            Interleave::Always => true,
            Interleave::Never => false,
            Interleave::Auto => {
                let bytes = std::mem::size_of_val(self.reader.leaves) + std::mem::size_of_val(self.reader.triangles);
                bytes > CACHED_BYTES && !coherent(rays, self.grid.tile_width)
            }
        }
    }

    /// Starts loading the triangles of the refs `passing`.
    #[inline(always)]
    fn prefetch_triangles(&self, passing: Passing<'_>) {
        for id in passing {
            if let Some(t) = self.reader.triangles.get(id as usize) {
                prefetch(t);
            }
        }
    }

    /// Runs the search of every ray of `rays`, [`IN_FLIGHT`] at a time: `start` makes a ray's
    /// state; for each leaf the ray reaches, `refs` chooses the refs to test (their triangles
    /// start loading), and on the lane's next turn `visit` tests them and says whether the ray's
    /// search is over; `finish(i, s)` receives the final state of ray `i` (`None` for a ray that misses
    /// the scene or is invalid). With `defer_origin` (any hit), the leaf a ray starts in is
    /// visited after the rest of its walk.
    #[inline(always)]
    fn interleaved<S>(
        &self,
        rays: &[Ray],
        defer_origin: bool,
        start: impl Fn(&Ray) -> S,
        refs: impl Fn(&S, &Leaf<'a>) -> Passing<'a>,
        visit: impl Fn(&TriRay, &Ray, &mut S, Passing<'a>, f64) -> bool,
        mut finish: impl FnMut(usize, Option<S>),
    ) {
        let origin = self.origin();
        let mut next = 0;
        // The next ray that reaches the scene, as a lane; the rays skipped on the way are
        // finished.
        let launch = |next: &mut usize, finish: &mut dyn FnMut(usize, Option<S>)| -> Option<Lane<'a, S>> {
            while let Some(ray) = rays.get(*next) {
                let index = *next;
                *next += 1;
                // An any-hit ray's walk, as the single-ray query's (`Setup::for_any_hit`).
                let setup = match self.setup(ray, origin) {
                    Some(setup) if defer_origin => Some(setup.for_any_hit(ray.tmax as f64, self.grid.radius)),
                    other => other.map(|setup| (setup, false)),
                };
                if let Some((setup, undecided)) = setup
                    && let Some(walk) = Walk::new(&self.reader, &self.grid, &setup)
                {
                    let tri_ray = TriRay::relative(ray, origin);
                    return Some(Lane {
                        index,
                        setup,
                        walk,
                        tri_ray,
                        state: start(ray),
                        pending: Pending::Nothing,
                        undecided,
                        deferred: None,
                    });
                }
                finish(index, None);
            }
            None
        };
        let mut lanes: [Option<Lane<'a, S>>; IN_FLIGHT] = std::array::from_fn(|_| None);
        for lane in &mut lanes {
            *lane = launch(&mut next, &mut finish);
        }
        let mut live = lanes.iter().filter(|l| l.is_some()).count();
        while live > 0 {
            for slot in &mut lanes {
                let Some(lane) = slot else { continue };
                // The leaf this lane reached on its last turn has had time to load: choose its refs
                // and ask for their triangles, to be tested on the next turn.
                // The first leaf with refs: put off if the ray starts in it (the walk then steps
                // on at once).
                if lane.undecided
                    && let Pending::Leaf(leaf) = lane.pending
                {
                    lane.undecided = false;
                    if leaf.enter_t == lane.setup.t0 {
                        lane.deferred = Some(leaf);
                        lane.pending = Pending::Nothing;
                    }
                }
                let mut done = match std::mem::replace(&mut lane.pending, Pending::Nothing) {
                    Pending::Leaf(leaf) => {
                        let chosen = refs(&lane.state, &leaf);
                        if chosen.is_done() {
                            visit(&lane.tri_ray, &rays[lane.index], &mut lane.state, chosen, leaf.exit_t)
                        } else {
                            self.prefetch_triangles(chosen.clone());
                            lane.pending = Pending::Refs(chosen, leaf.exit_t);
                            continue;
                        }
                    }
                    Pending::Refs(chosen, exit_t) => {
                        visit(&lane.tri_ray, &rays[lane.index], &mut lane.state, chosen, exit_t)
                    }
                    Pending::Nothing => false,
                };
                if !done {
                    match lane.walk.step(&self.grid, &lane.setup, &mut ()) {
                        Step::Leaf(leaf) => {
                            leaf.prefetch();
                            lane.pending = Pending::Leaf(leaf);
                        }
                        Step::Wait => {}
                        Step::End => match lane.deferred.take() {
                            Some(leaf) => {
                                leaf.prefetch();
                                lane.pending = Pending::Leaf(leaf);
                            }
                            None => done = true,
                        },
                    }
                }
                if done {
                    let Some(lane) = slot.take() else { continue };
                    finish(lane.index, Some(lane.state));
                    *slot = launch(&mut next, &mut finish);
                    if slot.is_none() {
                        live -= 1;
                    }
                }
            }
        }
    }
}

/// Whether most neighbours in `rays` start within [`NEAR_TILES`] tiles (of width `tile_width`) of
/// each other. Such rays read mostly the same tiles, or tiles of other directions around the same
/// place, which the rays before them brought into the cache; traced one after the other they wait
/// on little, and interleaving them would only add its bookkeeping. (Directions do not matter:
/// rays from one place in random directions still ran faster in turn.)
fn coherent(rays: &[Ray], tile_width: f64) -> bool {
    let reach = NEAR_TILES * tile_width;
    let near = |a: &Ray, b: &Ray| {
        let apart = (0..3).map(|k| (a.org[k] as f64 - b.org[k] as f64).powi(2)).sum::<f64>();
        apart < reach * reach
    };
    let close = rays.windows(2).filter(|w| near(&w[0], &w[1])).count();
    2 * close >= rays.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic sequence of numbers in `[0, 1)`.
    fn uniform(seed: u64) -> impl FnMut() -> f32 {
        let mut bits = crate::test_rng::xorshift(seed);
        move || (bits() >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn rays_starting_near_each_other_are_coherent_whatever_their_directions() {
        let mut next = uniform(5);
        let w = 0.01f32;
        let up = [0.0, 0.0, 1.0];
        // A camera's rays: one origin, many directions.
        let camera: Vec<Ray> =
            (0..WINDOW).map(|_| Ray::new([1.0, 2.0, 3.0], [next() - 0.5, next() - 0.5, next() - 0.5])).collect();
        assert!(coherent(&camera, w as f64));
        // Bounce rays from hits two tiles apart, in random directions.
        let bounces: Vec<Ray> = (0..WINDOW)
            .map(|i| Ray::new([2.0 * w * i as f32, 0.0, 0.0], [next() - 0.5, next() - 0.5, next() - 0.5]))
            .collect();
        assert!(coherent(&bounces, w as f64));
        // Neighbours five tiles apart (beyond NEAR_TILES), all in one direction.
        let apart: Vec<Ray> = (0..WINDOW).map(|i| Ray::new([5.0 * w * i as f32, 0.0, 0.0], up)).collect();
        assert!(!coherent(&apart, w as f64));
        // Origins spread over a scene a hundred tiles across.
        let spread: Vec<Ray> = (0..WINDOW).map(|_| Ray::new([100.0 * w * next(), next(), next()], up)).collect();
        assert!(!coherent(&spread, w as f64));
        // Pairs of rays from one place, the pairs far apart: half the neighbours are near.
        let pairs: Vec<Ray> = (0..WINDOW).map(|i| Ray::new([10.0 * w * (i / 2) as f32, 0.0, 0.0], up)).collect();
        assert!(coherent(&pairs, w as f64));
        // Every other ray far away: no two neighbours near.
        let alternate: Vec<Ray> =
            (0..WINDOW).map(|i| Ray::new([if i % 2 == 0 { 0.0 } else { 10.0 * w * i as f32 }, 0.0, 0.0], up)).collect();
        assert!(!coherent(&alternate, w as f64));
    }
}
