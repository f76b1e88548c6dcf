//! The ray query (paper §3.3 and §5), answered straight from the file bytes.
//!
//! 1. Clip the ray to the scene: its bounding sphere and its box, both grown by the margin `μ`.
//! 2. Choose the stored direction nearest the ray's by the constant-time lattice lookup, and rotate
//!    the ray into that direction's canonical frame.
//! 3. Walk, front to back, every tile its projection crosses (Amanatides and Woo 1987 in the
//!    tile grid; the paper's Figure 2: a ray not parallel to the beams crosses several tiles).
//! 4. In each tile, visit the leaves of its block (`formats/vlf.md` §5.6) that the ray's z range
//!    passes through, in ray order. A leaf's refs are first tested by their quantized boxes
//!    against the ray's box over the leaf (sixteen at a time, [`crate::filter`]); only those that
//!    pass reach the watertight triangle kernel.
//! 5. Stop as soon as the best hit lies within the part of the ray already searched.
//!
//! Triangles are stored relative to the scene's centre, and the ray is moved there first (in f64),
//! so a scene far from the world's origin keeps its precision ([`FieldView::closest_hit_local`]
//! takes rays already given relative to it).
//!
//! Geometry up to the triangle test is in f64, so its rounding stays far below the margin `μ` by
//! which the baker grew every footprint, z range and box (`formats/vlf.md` §6.2): the walk can only
//! see *more* candidates than the exact one, never fewer. Every index read from the file is
//! bounds-checked where it is used, so a file that passed the open checks but lies inside a section
//! yields wrong answers at worst, never a panic, an out-of-bounds read or unbounded work.

// Comparisons are written `!(a <= b)` on purpose throughout: a NaN (from a lying file) then takes
// the reject branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::filter::{Passing, limits};
use crate::prefetch::prefetch;
use vlf_format::block::{BOX_CELLS, Block, LeafRefs};
use vlf_format::{BeamRecord, EMPTY_TILE, FieldReader, LOOKUP_FLIP, LOOKUP_NONE, TriangleRecord, Z_LEVELS};
use vlf_geom::frame::mul;
use vlf_geom::{Closest, Counter, Hit, Ray, TriRay, Triangles};

/// The field's TRIANGLES section as the leaf kernel reads it.
struct FieldTriangles<'a>(&'a [TriangleRecord]);

impl Triangles for FieldTriangles<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<[[f32; 3]; 3]> {
        Some(self.0.get(id as usize)?.v)
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.0.len()
    }
}

/// The validated field plus the constants every query needs, derived once at open.
#[derive(Clone, Copy, Debug)]
pub struct FieldView<'a> {
    pub(crate) reader: FieldReader<'a>,
    n: usize,
    lattice_n: u32,
    center: [f64; 3],
    radius: f64,
    margin: f64,
    /// The scene's box relative to the centre, grown by the margin.
    box_lo: [f64; 3],
    box_hi: [f64; 3],
    tile_width: f64,
    inv_tile_width: f64,
    /// Box cells per world unit: `BOX_CELLS / tile_width`.
    cells_per_unit: f64,
    z_step: f64,
}

/// A ray in one direction's canonical frame, clipped to the scene.
struct Setup {
    dir: usize,
    /// Canonical origin (relative to the centre) and direction.
    o: [f64; 3],
    d: [f64; 3],
    /// The parameter range inside the (grown) scene and `[tmin, tmax]`.
    t0: f64,
    t1: f64,
    /// The beam coordinate in quantized levels (`formats/vlf.md` §5.6): `oq + t·dq`, and
    /// `1 / dq`; `up` if it grows along the ray.
    oq: f64,
    dq: f64,
    inv_dq: f64,
    up: bool,
}

/// The smaller of an interval end `a` and `b`; a NaN `b` (a lying file) leaves `a`.
#[inline(always)]
fn lower(a: f64, b: f64) -> f64 {
    if b < a { b } else { a }
}

/// The larger of an interval end `a` and `b`; a NaN `b` leaves `a`.
#[inline(always)]
fn higher(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// What to do after a leaf.
enum Visit {
    Continue,
    Done,
}

/// The ray over one tile in the tile's box cells (`formats/vlf.md` §5.6): its position is
/// `o + t·d` cells from the tile's corner, and `margin` is the margin `μ` in cells.
#[derive(Clone, Copy)]
struct CellRay {
    o: [f64; 2],
    d: [f64; 2],
    margin: f64,
}

impl CellRay {
    /// The limits of the box of cells the ray passes over `[t_a, t_b]`, grown by the margin.
    #[inline(always)]
    fn limits(&self, t_a: f64, t_b: f64) -> crate::filter::Limits {
        // Casts saturate: below 0 gives cell 0, above 255 cell 255 (and a NaN from a lying file
        // cell 0).
        const _: () = assert!(BOX_CELLS == 256, "cells are u8");
        let cell = |v: f64| v as u8;
        let (o, d, mu) = (self.o, self.d, self.margin);
        let (xa, xb) = (o[0] + t_a * d[0], o[0] + t_b * d[0]);
        let (ya, yb) = (o[1] + t_a * d[1], o[1] + t_b * d[1]);
        let (x_lo, x_hi) = if xa < xb { (xa, xb) } else { (xb, xa) };
        let (y_lo, y_hi) = if ya < yb { (ya, yb) } else { (yb, ya) };
        limits(cell(x_lo - mu), cell(x_hi + mu), cell(y_lo - mu), cell(y_hi + mu))
    }
}

/// What a visit of a leaf sees: the tile's block, the leaf's refs, and where the ray is.
struct Leaf<'b, 'a> {
    block: &'b Block<'a>,
    refs: LeafRefs,
    /// The ray parameters at which the ray enters and leaves the leaf.
    enter_t: f64,
    exit_t: f64,
    ray: CellRay,
}

impl<'a> Leaf<'_, 'a> {
    /// The ids of the leaf's refs whose boxes meet the ray's box over `[enter_t, t_far]` (the
    /// leaf, or the part of it before the best hit so far), grown by the margin.
    #[inline(always)]
    fn passing(&self, t_far: f64) -> Passing<'a> {
        Passing::new(self.block, self.refs, self.ray.limits(self.enter_t, t_far))
    }
}

impl<'a> FieldView<'a> {
    pub(crate) fn new(reader: FieldReader<'a>) -> Self {
        let p = reader.params;
        let s = reader.scene;
        let n = p.tile_resolution as usize;
        let tile_width = 2.0 * s.radius / n as f64;
        FieldView {
            reader,
            n,
            lattice_n: p.lattice_n,
            center: s.center,
            radius: s.radius,
            margin: p.margin,
            box_lo: s.aabb_min.map(|v| v - p.margin),
            box_hi: s.aabb_max.map(|v| v + p.margin),
            tile_width,
            inv_tile_width: 1.0 / tile_width,
            cells_per_unit: BOX_CELLS as f64 / tile_width,
            z_step: 2.0 * s.radius / Z_LEVELS as f64,
        }
    }

    /// The point the field's triangles are stored relative to: the centre of its scene, in world
    /// coordinates.
    pub fn origin(&self) -> [f64; 3] {
        self.center
    }

    /// The stored direction for ray direction `d` and the sign (+1 or −1) that makes the beam
    /// direction point the same way as `d`. Constant time: one division, at most three dot
    /// products (`formats/vlf.md` §5.3). `None` only if the file's lookup table lies (points at no
    /// stored direction).
    #[inline]
    pub fn select_direction(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        let sigma = if d[2] < 0.0 { -1.0 } else { 1.0 };
        let q = [d[0] * sigma, d[1] * sigma, d[2] * sigma];
        let (ax, ay) = (q[0].abs(), q[1].abs());
        let n = self.lattice_n as i64;
        let nf = n as f64;
        let scale = nf / (ax + ay + q[2]);
        let (u, v) = ((ax * scale).min(nf), (ay * scale).min(nf));
        // Truncation is floor for these non-negative values (no libm call).
        let (i, k) = (u as i64, v as i64);
        let lower = (u - i as f64) + (v - k as f64) < 1.0;
        let cells = if lower { [(i, k), (i + 1, k), (i, k + 1)] } else { [(i + 1, k), (i, k + 1), (i + 1, k + 1)] };
        let (sx, sy) = (if q[0] < 0.0 { -1 } else { 1 }, if q[1] < 0.0 { -1 } else { 1 });
        let side = 2 * n + 1;
        let entry_at = |ci: i64, ck: i64| self.reader.lookup.get(((sy * ck + n) * side + (sx * ci + n)) as usize);
        let mut best: Option<(usize, f64)> = None;
        let mut best_dot = f64::NEG_INFINITY;
        for (ci, ck) in cells {
            if ci + ck > n {
                continue;
            }
            let Some(&entry) = entry_at(ci, ck) else { continue };
            if entry == LOOKUP_NONE {
                continue;
            }
            let j = (entry & !LOOKUP_FLIP) as usize;
            let Some(w) = self.reader.directions.get(j) else { continue };
            let s = if entry & LOOKUP_FLIP != 0 { -1.0 } else { 1.0 };
            let dot = s * (w[0] as f64 * q[0] + w[1] as f64 * q[1] + w[2] as f64 * q[2]);
            if dot > best_dot {
                best_dot = dot;
                best = Some((j, sigma * s));
            }
        }
        if best.is_none() {
            // Only reachable through rounding at the rim: the clamped corner is a lattice point.
            let ci = i.min(n);
            let entry = *entry_at(ci, k.min(n - ci))?;
            let j = (entry & !LOOKUP_FLIP) as usize;
            if entry != LOOKUP_NONE && j < self.reader.directions.len() {
                best = Some((j, if entry & LOOKUP_FLIP != 0 { -sigma } else { sigma }));
            }
        }
        best
    }

    /// Steps 1 and 2 for a ray whose origin is given relative to `origin` (the world's origin for
    /// world rays: the ray is moved to the centre here).
    #[inline]
    fn setup(&self, ray: &Ray, origin: [f64; 3]) -> Option<Setup> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.dir.map(f64::from);
        let oc: [f64; 3] = std::array::from_fn(|i| ray.org[i] as f64 - origin[i]);
        // Clip to the scene's box grown by the margin: rays from outside start where the scene
        // starts. (Every point of the box that is outside the bounding sphere holds no triangle;
        // the walk clamps it to the grid.) `max` and `min` ignore a NaN from `0 · ∞`, which
        // leaves the interval as it was: conservative.
        let mut t0 = ray.tmin as f64;
        let mut t1 = ray.tmax as f64;
        for k in 0..3 {
            if d[k] != 0.0 {
                let inv = 1.0 / d[k];
                let ta = (self.box_lo[k] - oc[k]) * inv;
                let tb = (self.box_hi[k] - oc[k]) * inv;
                let (near, far) = if inv < 0.0 { (tb, ta) } else { (ta, tb) };
                t0 = higher(t0, near);
                t1 = lower(t1, far);
            } else if !(oc[k] >= self.box_lo[k] && oc[k] <= self.box_hi[k]) {
                return None;
            }
        }
        if !(t0 <= t1) {
            return None;
        }
        let (dir, sign) = self.select_direction(d)?;
        let m = self.reader.rotations.get(dir)?;
        let o = mul(m, oc);
        let dc = mul(m, d);
        // Only a lying file can make the beam coordinate stand still or turn non-finite.
        if !(dc[2] * sign > 0.0) || !o.iter().chain(&dc).all(|v| v.is_finite()) {
            return None;
        }
        let inv_step = 1.0 / self.z_step;
        let (oq, dq) = ((o[2] + self.radius) * inv_step, dc[2] * inv_step);
        Some(Setup { dir, o, d: dc, t0, t1, oq, dq, inv_dq: 1.0 / dq, up: dq > 0.0 })
    }

    /// The closest hit on `[tmin, tmax]` of a ray in world coordinates, or `None`:
    /// [`crate::Field::closest_hit`].
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_counted(ray, &mut ())
    }

    /// [`Self::closest_hit`], counting the work done in `counter` (rays, tiles, leaves and
    /// triangle tests; `()` counts nothing).
    pub fn closest_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.closest(ray, self.center, counter)
    }

    /// The closest hit of a ray whose origin is given relative to [`Self::origin`] (the
    /// scene's centre): for scenes far from the world's origin, where an f32 world origin
    /// cannot be precise. `t`, `u`, `v` and `prim` mean what they mean for world rays.
    #[inline]
    pub fn closest_hit_local(&self, ray: &Ray) -> Option<Hit> {
        self.closest(ray, [0.0; 3], &mut ())
    }

    /// Whether anything is hit on `[tmin, tmax]`; the first hit found ends the search:
    /// [`crate::Field::any_hit`].
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit_counted(ray, &mut ()).is_some()
    }

    /// The first hit found on `[tmin, tmax]` (not necessarily the closest), counting the work.
    pub fn any_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        self.any(ray, self.center, counter)
    }

    /// [`Self::any_hit`] for a ray given relative to [`Self::origin`].
    #[inline]
    pub fn any_hit_local(&self, ray: &Ray) -> bool {
        self.any(ray, [0.0; 3], &mut ()).is_some()
    }

    #[inline(always)]
    fn closest(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray, origin)?;
        counter.ray();
        let tri_ray = TriRay::relative(ray, origin);
        let tris = FieldTriangles(self.reader.triangles);
        let mut best = Closest::new(ray.tmax);
        self.walk(&setup, counter, |leaf, counter| {
            let t_far = lower(leaf.exit_t, best.tmax as f64);
            tri_ray.closest_in(&tris, leaf.passing(t_far), &mut best, counter);
            // Final once the best hit lies within the part of the ray already searched.
            if best.hit.is_some() && (best.tmax as f64) <= leaf.exit_t { Visit::Done } else { Visit::Continue }
        });
        best.hit
    }

    #[inline(always)]
    fn any(&self, ray: &Ray, origin: [f64; 3], counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray, origin)?;
        counter.ray();
        let tri_ray = TriRay::relative(ray, origin);
        let tris = FieldTriangles(self.reader.triangles);
        let mut found = None;
        self.walk(&setup, counter, |leaf, counter| {
            found = tri_ray.any_in(&tris, leaf.passing(leaf.exit_t), ray.tmax, counter);
            if found.is_some() { Visit::Done } else { Visit::Continue }
        });
        found
    }

    /// [`Self::closest_hit_local`] with the triangles read through `tris` instead of the field's
    /// TRIANGLES, counting the work: an id whose `tris.vertices(id)` is `None` is skipped, as the
    /// kernel skips ids a damaged file names. For callers that hide some of a field's triangles
    /// without writing its bytes (`vlf-scene`'s edits). The walk is [`Self::closest_hit`]'s.
    pub fn closest_hit_local_in(&self, ray: &Ray, tris: &impl Triangles, counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray, [0.0; 3])?;
        counter.ray();
        let tri_ray = TriRay::relative(ray, [0.0; 3]);
        let mut best = Closest::new(ray.tmax);
        self.walk(&setup, counter, |leaf, counter| {
            let t_far = lower(leaf.exit_t, best.tmax as f64);
            tri_ray.closest_in(tris, leaf.passing(t_far), &mut best, counter);
            if best.hit.is_some() && (best.tmax as f64) <= leaf.exit_t { Visit::Done } else { Visit::Continue }
        });
        best.hit
    }

    /// [`Self::any_hit_local`] with the triangles read through `tris`, as
    /// [`Self::closest_hit_local_in`]; the first hit found, counting the work.
    pub fn any_hit_local_in(&self, ray: &Ray, tris: &impl Triangles, counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray, [0.0; 3])?;
        counter.ray();
        let tri_ray = TriRay::relative(ray, [0.0; 3]);
        let mut found = None;
        self.walk(&setup, counter, |leaf, counter| {
            found = tri_ray.any_in(tris, leaf.passing(leaf.exit_t), ray.tmax, counter);
            if found.is_some() { Visit::Done } else { Visit::Continue }
        });
        found
    }

    /// The ray's candidate set (the paper's potentially visible set), leaf by leaf in ray order:
    /// calls `visit(ids, exit_t)` with the triangle ids of each visited leaf (before the box test)
    /// and the ray parameter at which the ray leaves that leaf, until `visit` returns `true`. A
    /// triangle may appear in several leaves. This is the walk [`Self::closest_hit`] does, without
    /// the box and triangle tests.
    pub fn for_each_leaf(&self, ray: &Ray, counter: &mut impl Counter, mut visit: impl FnMut(&[u32], f64) -> bool) {
        if let Some(setup) = self.setup(ray, self.center) {
            self.walk(&setup, counter, |leaf, _| {
                if visit(leaf.block.ids(leaf.refs), leaf.exit_t) { Visit::Done } else { Visit::Continue }
            });
        }
    }

    /// The walk of the all-hits query (`crate::all_hits`): calls `visit(passing, exit_t)` for each
    /// leaf along the ray, front to back, until it returns `true`; `passing(t_far)` gives the ids
    /// of the leaf's refs whose boxes meet the ray's box over `[enter_t, t_far]`, as
    /// [`Self::closest_hit`] tests them.
    pub(crate) fn for_each_leaf_filtered(
        &self,
        ray: &Ray,
        mut visit: impl FnMut(&dyn Fn(f64) -> Passing<'a>, f64) -> bool,
    ) {
        if let Some(setup) = self.setup(ray, self.center) {
            self.walk(&setup, &mut (), |leaf, _| {
                if visit(&|t_far| leaf.passing(t_far), leaf.exit_t) { Visit::Done } else { Visit::Continue }
            });
        }
    }

    /// Steps 3 to 5: visits the leaves along the ray front to back, handing each to `visit` until
    /// it says `Done`.
    #[inline(always)]
    fn walk<C: Counter>(&self, s: &Setup, counter: &mut C, mut visit: impl FnMut(&Leaf<'_, 'a>, &mut C) -> Visit) {
        let Some(beam) = self.reader.beams.get(s.dir) else { return };
        let n = self.n as i64;
        let (w, r) = (self.tile_width, self.radius);
        // Tile coordinates of the entry point, clamped: the grown scene pokes out of the grid by
        // at most the margin, where no triangle lies.
        // (Truncation equals floor under the clamp to [0, n−1], without a libm call.)
        let cell = |v: f64| (((v + r) * self.inv_tile_width) as i64).clamp(0, n - 1);
        let mut ix = cell(s.o[0] + s.t0 * s.d[0]);
        let mut iy = cell(s.o[1] + s.t0 * s.d[1]);
        // Parameter of the next tile boundary on each axis, and the parameter step between them.
        let axis = |i: i64, o: f64, d: f64| -> (i64, f64, f64) {
            if d > 0.0 {
                (1, ((i + 1) as f64 * w - r - o) / d, w / d)
            } else if d < 0.0 {
                (-1, (i as f64 * w - r - o) / d, -w / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (step_x, mut next_x, delta_x) = axis(ix, s.o[0], s.d[0]);
        let (step_y, mut next_y, delta_y) = axis(iy, s.o[1], s.d[1]);
        let tiles_of_dir = self.n * self.n * s.dir;
        let mut t_enter = s.t0;
        // Each step moves one axis monotonically, so 2n + 1 visits cover any segment.
        for _ in 0..=2 * n {
            let t_exit = lower(lower(next_x, next_y), s.t1);
            counter.cell();
            // Start loading the next tile's block while this one is visited.
            if t_exit < s.t1 {
                let (nx, ny) = if next_x <= next_y { (ix + step_x, iy) } else { (ix, iy + step_y) };
                if (0..n).contains(&nx) && (0..n).contains(&ny) {
                    if let Some(&next) = self.reader.tiles.get(tiles_of_dir + ny as usize * self.n + nx as usize) {
                        if let Some(word) =
                            self.reader.leaves.get((beam.leaves_base as usize).wrapping_add(next as usize))
                        {
                            prefetch(word);
                        }
                    }
                }
            }
            if let Some(&entry) = self.reader.tiles.get(tiles_of_dir + iy as usize * self.n + ix as usize) {
                if entry != EMPTY_TILE {
                    if let Some(block) = self.block(beam, entry) {
                        let corner = [-r + ix as f64 * w, -r + iy as f64 * w];
                        if let Visit::Done = self.visit_tile(&block, corner, s, t_enter, t_exit, counter, &mut visit) {
                            return;
                        }
                    }
                }
            }
            if t_exit >= s.t1 {
                return;
            }
            if next_x <= next_y {
                ix += step_x;
                t_enter = next_x;
                next_x += delta_x;
            } else {
                iy += step_y;
                t_enter = next_y;
                next_y += delta_y;
            }
            if !(0..n).contains(&ix) || !(0..n).contains(&iy) {
                return;
            }
        }
    }

    /// The block of a tile whose TILES entry is `entry`, if the file's offsets are sane.
    #[inline(always)]
    fn block(&self, beam: &BeamRecord, entry: u32) -> Option<Block<'a>> {
        let at = (beam.leaves_base as usize).checked_add(entry as usize)?;
        Block::parse(self.reader.leaves.get(at..)?)
    }

    /// Visits the leaves of one tile (square at `corner`) that the ray's parameter range
    /// `[t_enter, t_exit]` reaches, in ray order.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn visit_tile<C: Counter>(
        &self,
        block: &Block<'a>,
        corner: [f64; 2],
        s: &Setup,
        t_enter: f64,
        t_exit: f64,
        counter: &mut C,
        visit: &mut impl FnMut(&Leaf<'_, 'a>, &mut C) -> Visit,
    ) -> Visit {
        let bounds = block.bounds();
        let k = block.leaf_count();
        let t_at = |level: u16| (level as f64 - s.oq) * s.inv_dq;
        // The parameter range over which the ray is within the tile's z range.
        let up = s.up;
        let (ta, tb) = if up { (t_at(bounds[0]), t_at(bounds[k])) } else { (t_at(bounds[k]), t_at(bounds[0])) };
        let lo = higher(t_enter, ta);
        let hi = lower(t_exit, tb);
        if !(lo <= hi) {
            return Visit::Continue;
        }
        // The leaf holding the entry point: the leaves partition [bounds[0], bounds[K]] in order.
        // Going up, the first leaf whose top is not below it; going down, the last whose bottom
        // is not above it.
        let q_in = s.oq + lo * s.dq;
        let inner = &bounds[1..k];
        let mut leaf = if up {
            inner.partition_point(|&b| (b as f64) < q_in)
        } else {
            inner.partition_point(|&b| (b as f64) <= q_in)
        };
        let c = self.cells_per_unit;
        let ray = CellRay {
            o: [(s.o[0] - corner[0]) * c, (s.o[1] - corner[1]) * c],
            d: [s.d[0] * c, s.d[1] * c],
            margin: self.margin * c,
        };
        let mut leaf_enter = lo;
        loop {
            let last = if up { leaf + 1 == k } else { leaf == 0 };
            let exit_t = if last { hi } else { lower(t_at(bounds[if up { leaf + 1 } else { leaf }]), hi) };
            counter.leaf();
            // Start loading the next leaf's boxes while this one is tested.
            if !last {
                if let Some(next) = block.leaf(if up { leaf + 1 } else { leaf - 1 }) {
                    if let Some(b) = block.leaf_bytes(next).first() {
                        prefetch(b);
                    }
                }
            }
            if let Some(refs) = block.leaf(leaf).filter(|r| !r.is_empty()) {
                let l = Leaf { block, refs, enter_t: leaf_enter, exit_t, ray };
                if let Visit::Done = visit(&l, counter) {
                    return Visit::Done;
                }
            }
            if last || exit_t >= hi {
                return Visit::Continue;
            }
            leaf_enter = exit_t;
            if up {
                leaf += 1;
            } else {
                leaf -= 1;
            }
        }
    }
}
