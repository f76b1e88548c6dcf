//! The ray query (paper §3.3 and §5), answered straight from the file bytes.
//!
//! 1. Choose the stored direction nearest the ray's by the constant-time lattice lookup.
//! 2. Rotate the ray into that direction's canonical frame and clip it to the bounding sphere.
//! 3. Walk, front to back, every tile its projection crosses (Amanatides and Woo 1987 in the
//!    tile grid; the paper's Figure 2: a ray not parallel to the beams crosses several tiles).
//! 4. In each tile, visit the 1D-BSP leaves the ray's z range passes through, in ray order, and
//!    test their triangles with the watertight kernel.
//! 5. Stop as soon as the best hit lies within the part of the ray already searched.
//!
//! Geometry up to the triangle test is in f64, so its rounding stays far below the margin `μ` by
//! which the baker grew every footprint (`formats/vlf.md` §6.2): the walk can only see *more*
//! candidates than the exact one, never fewer. Every index read from the file is bounds-checked
//! where it is used, so a file that passed the open checks but lies inside a section yields wrong
//! answers at worst, never a panic or an out-of-bounds read.

// Comparisons are written `!(a <= b)` on purpose throughout: a NaN (from a lying file) then takes
// the reject branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use vlf_format::{BeamRecord, FieldReader, LOOKUP_FLIP, LOOKUP_NONE, MAX_DEPTH, TileRecord, TriangleRecord, Z_LEVELS};
use vlf_geom::frame::mul;
use vlf_geom::lattice::candidates;
use vlf_geom::{Closest, Counter, Hit, Ray, TriRay, Triangles};

/// The field's TRIANGLES section as the leaf kernel reads it.
struct FieldTriangles<'a>(&'a [TriangleRecord]);

impl Triangles for FieldTriangles<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<[[f32; 3]; 3]> {
        let t = self.0.get(id as usize)?;
        Some([t.vertex(0), t.vertex(1), t.vertex(2)])
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
    clip_radius_sq: f64,
    tile_width: f64,
    inv_tile_width: f64,
    z_step: f64,
}

/// A ray in one direction's canonical frame, clipped to the sphere.
struct Setup {
    dir: usize,
    /// Canonical origin (relative to the centre) and direction.
    o: [f64; 3],
    d: [f64; 3],
    /// The parameter range inside the (grown) bounding sphere and `[tmin, tmax]`.
    t0: f64,
    t1: f64,
}

/// The outcome of visiting one leaf.
enum Visit {
    Continue,
    Done,
}

impl<'a> FieldView<'a> {
    pub(crate) fn new(reader: FieldReader<'a>) -> Self {
        let p = reader.params;
        let s = reader.scene;
        let n = p.tile_resolution as usize;
        let grown = s.radius + p.margin;
        let tile_width = 2.0 * s.radius / n as f64;
        FieldView {
            reader,
            n,
            lattice_n: p.lattice_n,
            center: s.center,
            radius: s.radius,
            clip_radius_sq: grown * grown,
            tile_width,
            inv_tile_width: 1.0 / tile_width,
            z_step: 2.0 * s.radius / Z_LEVELS as f64,
        }
    }

    /// The stored direction for ray direction `d` and the sign (+1 or −1) that makes the beam
    /// direction point the same way as `d`. Constant time: one division, three dot products.
    /// `None` only if the file's lookup table lies (points at no stored direction).
    #[inline]
    pub fn select_direction(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        let sigma = if d[2] < 0.0 { -1.0 } else { 1.0 };
        let q = [d[0] * sigma, d[1] * sigma, d[2] * sigma];
        let n = self.lattice_n as i32;
        let side = 2 * n + 1;
        let mut best: Option<(usize, f64)> = None;
        let mut best_dot = f64::NEG_INFINITY;
        for &(i, k) in candidates(self.lattice_n, q[0].abs(), q[1].abs(), q[2]).as_slice() {
            let a = if q[0] < 0.0 { -(i as i32) } else { i as i32 };
            let b = if q[1] < 0.0 { -(k as i32) } else { k as i32 };
            let Some(&entry) = self.reader.lookup.get(((b + n) * side + (a + n)) as usize) else { continue };
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
        best
    }

    /// Steps 1 and 2: direction, canonical frame, sphere clip.
    #[inline]
    fn setup(&self, ray: &Ray) -> Option<Setup> {
        if !ray.is_valid() {
            return None;
        }
        let d = ray.dir.map(f64::from);
        let oc: [f64; 3] = std::array::from_fn(|i| ray.org[i] as f64 - self.center[i]);
        // Clip to the bounding sphere grown by the margin, with the cancellation-free quadratic.
        let a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
        let c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - self.clip_radius_sq;
        let disc = b * b - a * c;
        if !(disc >= 0.0) {
            return None;
        }
        let q = -(b + disc.sqrt().copysign(b));
        let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
        let t0 = r0.min(r1).max(ray.tmin as f64);
        let t1 = r0.max(r1).min(ray.tmax as f64);
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
        Some(Setup { dir, o, d: dc, t0, t1 })
    }

    /// The closest hit on `[tmin, tmax]`, or `None`: [`crate::Field::closest_hit`].
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_hit_counted(ray, &mut ())
    }

    /// [`Self::closest_hit`], counting the work done in `counter` (rays, tiles, leaves and
    /// triangle tests; `()` counts nothing).
    pub fn closest_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray)?;
        counter.ray();
        let tri_ray = TriRay::new(ray);
        let tris = FieldTriangles(self.reader.triangles);
        let mut best = Closest::new(ray.tmax);
        self.walk(&setup, counter, |ids, exit_t, counter| {
            tri_ray.closest_in(&tris, ids.iter().copied(), &mut best, counter);
            // Final once the best hit lies within the part of the ray already searched.
            if best.hit.is_some() && (best.tmax as f64) <= exit_t { Visit::Done } else { Visit::Continue }
        });
        best.hit
    }

    /// Whether anything is hit on `[tmin, tmax]`; the first hit found ends the search:
    /// [`crate::Field::any_hit`].
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit_counted(ray, &mut ()).is_some()
    }

    /// The first hit found on `[tmin, tmax]` (not necessarily the closest), counting the work.
    pub fn any_hit_counted(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        let setup = self.setup(ray)?;
        counter.ray();
        let tri_ray = TriRay::new(ray);
        let tris = FieldTriangles(self.reader.triangles);
        let mut found = None;
        self.walk(&setup, counter, |ids, _, counter| {
            found = tri_ray.any_in(&tris, ids.iter().copied(), ray.tmax, counter);
            if found.is_some() { Visit::Done } else { Visit::Continue }
        });
        found
    }

    /// The ray's candidate set (the paper's potentially visible set), leaf by leaf in ray order:
    /// calls `visit(ids, exit_t)` with each visited leaf's triangle ids and the ray parameter at
    /// which the ray leaves that leaf, until `visit` returns `true`. A triangle may appear in
    /// several leaves. This is the walk [`Self::closest_hit`] does, without the triangle tests.
    pub fn for_each_leaf(&self, ray: &Ray, counter: &mut impl Counter, mut visit: impl FnMut(&[u32], f64) -> bool) {
        if let Some(setup) = self.setup(ray) {
            self.walk(&setup, counter, |ids, exit_t, _| if visit(ids, exit_t) { Visit::Done } else { Visit::Continue });
        }
    }

    /// Steps 3 to 5: visits the leaves along the ray front to back, handing each leaf's ids and
    /// the ray parameter at which the ray leaves that leaf to `visit`, until it says `Done`.
    #[inline(always)]
    fn walk<C: Counter>(&self, s: &Setup, counter: &mut C, mut visit: impl FnMut(&[u32], f64, &mut C) -> Visit) {
        let Some(beam) = self.reader.beams.get(s.dir) else { return };
        let n = self.n as i64;
        let (w, r) = (self.tile_width, self.radius);
        // Tile coordinates of the entry point, clamped: the grown sphere pokes out of the square
        // by at most the margin, where no triangle lies.
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
            let t_exit = next_x.min(next_y).min(s.t1);
            let index = tiles_of_dir + iy as usize * self.n + ix as usize;
            if let Some(tile) = self.reader.tiles.get(index) {
                counter.cell();
                if let Visit::Done = self.visit_tile(tile, beam, s, t_enter, t_exit, counter, &mut visit) {
                    return;
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

    /// Visits the leaves of one tile that the ray's parameter range `[t_enter, t_exit]` reaches.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn visit_tile<C: Counter>(
        &self,
        tile: &TileRecord,
        beam: &BeamRecord,
        s: &Setup,
        t_enter: f64,
        t_exit: f64,
        counter: &mut C,
        visit: &mut impl FnMut(&[u32], f64, &mut C) -> Visit,
    ) -> Visit {
        if tile.is_empty() || tile.depth as u32 > MAX_DEPTH {
            return Visit::Continue;
        }
        let count = 1i64 << tile.depth;
        // File-supplied bases: saturate, so an absurd value fails the bounds check instead of
        // overflowing. An honest tile's leaves lie inside LEAF_BOUNDS (`formats/vlf.md` §5.6);
        // skipping a tile that claims more keeps a lying depth from making the loop below
        // iterate up to 2^24 times over leaves that do not exist.
        let base = (beam.leaf_base as usize).saturating_add(tile.first_leaf as usize);
        if base.saturating_add(count as usize) >= self.reader.leaf_bounds.len() {
            return Visit::Continue;
        }
        let z0 = -self.radius + tile.z_lo as f64 * self.z_step;
        let z1 = -self.radius + tile.z_hi as f64 * self.z_step;
        let (oz, dz) = (s.o[2], s.d[2]);
        // The parameter range over which the ray's beam coordinate is within [z0, z1].
        let (ta, tb) = if dz > 0.0 { ((z0 - oz) / dz, (z1 - oz) / dz) } else { ((z1 - oz) / dz, (z0 - oz) / dz) };
        let lo = t_enter.max(ta);
        let hi = t_exit.min(tb);
        if !(lo <= hi) {
            return Visit::Continue;
        }
        let h = (z1 - z0) / count as f64;
        let leaf_of = |t: f64| (((oz + t * dz - z0) / h) as i64).clamp(0, count - 1);
        let (first, last) = (leaf_of(lo), leaf_of(hi));
        let step = if dz > 0.0 { 1 } else { -1 };
        let mut k = first;
        loop {
            let leaf_exit = if k == last {
                hi
            } else {
                let boundary = z0 + (if dz > 0.0 { k + 1 } else { k }) as f64 * h;
                ((boundary - oz) / dz).min(hi)
            };
            counter.leaf();
            if let Some(ids) = self.leaf_ids(beam, base.saturating_add(k as usize)) {
                if let Visit::Done = visit(ids, leaf_exit, counter) {
                    return Visit::Done;
                }
            }
            if k == last {
                return Visit::Continue;
            }
            k += step;
        }
    }

    /// The ids of leaf `leaf` (an index into LEAF_BOUNDS), if the file's bounds are sane.
    #[inline(always)]
    fn leaf_ids(&self, beam: &BeamRecord, leaf: usize) -> Option<&'a [u32]> {
        let b = self.reader.leaf_bounds.get(leaf..leaf.checked_add(2)?)?;
        let base = beam.id_base as usize;
        self.reader.triangle_ids.get(base.checked_add(b[0] as usize)?..base.checked_add(b[1] as usize)?)
    }
}
