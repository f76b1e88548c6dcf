//! Steps 3 and 4 of the query ([`crate::query`]): the tiles a ray's projection crosses, front to
//! back (Amanatides and Woo 1987 in the tile grid), and in each the leaves of its block
//! (`formats/vlf.md` §5.6) that the ray's z range passes through, in ray order.
//!
//! The walk comes in two forms over the same parts (the grid step [`Dda`], a direction's tiles
//! [`Beam`], a tile's leaves [`Tile`]): plain loops ([`walk_leaves`], for the all-hits queries and
//! [`crate::FieldView::for_each_leaf`]), and a resumable cursor ([`Walk`]) that a batch
//! ([`crate::batch`]) advances for several rays in turn, starting to load what each one needs next
//! before coming back to it, so that their cache misses overlap. The single-ray closest-hit and
//! any-hit queries run the same tiles and leaves in the same order as a loop nest of their own
//! ([`crate::trace`], measured faster than these parts assembled; its any-hit search puts off the
//! leaf the ray starts in until the rest is searched, or walks a segment that leaves the scene
//! from its far end: [`Setup::for_any_hit`]). All see the same tiles and leaves, closest
//! hits in the same order, and the closest hit does not depend on the order of the tests
//! ([`vlf_geom::Closest::take`]) nor whether anything is hit on the order of the leaves, so they
//! give the same answers.
//!
//! Geometry here is in f64: its rounding stays far below the margin `μ` by which the baker grew
//! every footprint, z range and box (`formats/vlf.md` §6.2). Every index read from the file is
//! bounds-checked where it is used: a lying file yields wrong answers at worst, never a panic or
//! unbounded work (a ray visits at most `2n + 1` tiles and, in each, at most its `K` leaves).

// Comparisons are written `!(a <= b)` on purpose: a NaN (from a lying file) takes the reject
// branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::filter::{Limits, Passing, segment_limits};
use crate::prefetch::prefetch;
use vlf_format::block::{BOX_CELLS, Block};
use vlf_format::{EMPTY_TILE, FieldReader, TriangleRecord};
use vlf_geom::Counter;

/// The smaller of an interval end `a` and `b`; a NaN `b` (a lying file) leaves `a`.
#[inline(always)]
pub(crate) fn lower(a: f64, b: f64) -> f64 {
    if b < a { b } else { a }
}

/// The larger of an interval end `a` and `b`; a NaN `b` leaves `a`.
#[inline(always)]
pub(crate) fn higher(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// The field's tile grid as the walk sees it, derived once at open.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    /// Tiles per side, `n`.
    pub(crate) n: usize,
    /// The bounding sphere's radius: the grid spans `[−radius, radius]²` in a direction's frame.
    pub(crate) radius: f64,
    pub(crate) tile_width: f64,
    pub(crate) inv_tile_width: f64,
    /// Box cells per world unit: `BOX_CELLS / tile_width`.
    pub(crate) cells_per_unit: f64,
    /// The margin `μ`.
    pub(crate) margin: f64,
}

/// A ray in one direction's canonical frame, clipped to the scene (steps 1 and 2 of the query).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup {
    pub(crate) dir: usize,
    /// Canonical origin (relative to the centre) and direction.
    pub(crate) o: [f64; 3],
    pub(crate) d: [f64; 3],
    /// The parameter range inside the (grown) scene and `[tmin, tmax]`.
    pub(crate) t0: f64,
    pub(crate) t1: f64,
    /// The beam coordinate in quantized levels (`formats/vlf.md` §5.6): `oq + t·dq`, and
    /// `1 / dq`; `up` if it grows along the ray.
    pub(crate) oq: f64,
    pub(crate) dq: f64,
    pub(crate) inv_dq: f64,
    pub(crate) up: bool,
}

/// How far from the scene's centre, in radii, a ray may start for an any-hit search to walk it
/// from its far end: 2²⁶ (about 6.7 · 10⁷).
const NEAR_ORIGIN: f64 = (1u64 << 26) as f64;

impl Setup {
    /// The same segment walked from its far end: the ray reversed, starting at `t1`. Its walk
    /// visits the tiles and leaves of this one in the opposite order (the grid is the same and
    /// the rounding of the reversed origin, far below the margin, is covered by it); a ray
    /// parameter `t'` of it is `t1 − t'` of this one.
    pub(crate) fn reversed(&self) -> Setup {
        let (o, d, t1) = (self.o, self.d, self.t1);
        Setup {
            dir: self.dir,
            o: [o[0] + t1 * d[0], o[1] + t1 * d[1], o[2] + t1 * d[2]],
            d: [-d[0], -d[1], -d[2]],
            t0: 0.0,
            t1: t1 - self.t0,
            oq: self.oq + t1 * self.dq,
            dq: -self.dq,
            inv_dq: -self.inv_dq,
            up: !self.up,
        }
    }

    /// The walk of an any-hit search for a ray ending at `tmax`, in a scene of `radius`, and
    /// whether it puts off the leaf where it starts: a segment that leaves the scene (ends before
    /// `tmax`) is walked from that far end, if its origin is near enough for the far end to be
    /// computed to well within the margin (within [`NEAR_ORIGIN`] radii: the range
    /// `formats/vlf.md` §6.2 guarantees, 10⁸ R, with room to spare), through the scene's emptier margins
    /// first and its origin's crowded surroundings last; a segment that ends inside the scene
    /// (ambient occlusion) from its origin, putting off the leaf of the surface it leaves
    /// ([`crate::trace`]'s `OriginLeaf`). Either way every leaf the segment passes is searched
    /// unless a hit is found, so the answer is the same; only which hit is found, and how soon,
    /// differ.
    pub(crate) fn for_any_hit(self, tmax: f64, radius: f64) -> (Setup, bool) {
        let near = self.o.iter().all(|c| c.abs() <= NEAR_ORIGIN * radius);
        if self.t1 < tmax && near { (self.reversed(), false) } else { (self, true) }
    }
}

impl Setup {
    /// The ray parameter at which the beam coordinate reaches quantized `level`.
    #[inline(always)]
    pub(crate) fn t_at(&self, level: u16) -> f64 {
        (level as f64 - self.oq) * self.inv_dq
    }
}

/// The ray over one tile in the tile's box cells (`formats/vlf.md` §5.6): its position is
/// `o + t·d` cells from the tile's corner, and `margin` is the margin `μ` in cells.
#[derive(Clone, Copy, Debug)]
struct CellRay {
    o: [f64; 2],
    d: [f64; 2],
    margin: f64,
}

impl CellRay {
    /// The limits of the box of cells the ray passes over `[t_a, t_b]`, grown by the margin
    /// (bounds below cell 0 give cell 0, above 255 cell 255).
    #[inline(always)]
    fn limits(&self, t_a: f64, t_b: f64) -> Limits {
        const _: () = assert!(BOX_CELLS == 256, "cells are u8");
        let (o, d) = (self.o, self.d);
        segment_limits([o[0] + t_a * d[0], o[1] + t_a * d[1]], [o[0] + t_b * d[0], o[1] + t_b * d[1]], self.margin)
    }
}

/// A leaf the walk reached: its refs, and where the ray is.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Leaf<'a> {
    /// The leaf's bytes from its first box array on ([`Block::leaf_bytes`]), and its number of
    /// refs.
    bytes: &'a [u8],
    len: usize,
    /// The ray parameters at which the ray enters and leaves the leaf.
    pub(crate) enter_t: f64,
    pub(crate) exit_t: f64,
    ray: CellRay,
}

impl<'a> Leaf<'a> {
    /// The ids of the leaf's refs whose boxes meet the ray's box over `[enter_t, t_far]` (the
    /// leaf, or the part of it before the best hit so far), grown by the margin. The records in
    /// `load` of each group of passing refs start loading as soon as the group is found, so that
    /// their cache misses overlap: a single ray's query passes the field's triangles, a batch
    /// (which overlaps misses across rays instead) `&[]`.
    #[inline(always)]
    pub(crate) fn passing(&self, t_far: f64, load: &'a [TriangleRecord]) -> Passing<'a> {
        Passing::new(self.bytes, self.len, self.ray.limits(self.enter_t, t_far), load)
    }

    /// The triangle ids of all the leaf's refs, before the box test.
    #[inline(always)]
    pub(crate) fn ids(&self) -> &'a [u32] {
        vlf_format::block::leaf_ids(self.bytes, self.len)
    }

    /// Starts loading the leaf's boxes and ids.
    #[inline(always)]
    pub(crate) fn prefetch(&self) {
        if let Some(b) = self.bytes.first() {
            prefetch(b);
        }
        if let Some(b) = self.bytes.get(4 * self.len) {
            prefetch(b);
        }
    }
}

/// One step of a [`Walk`].
pub(crate) enum Step<'a> {
    /// The next leaf along the ray that holds refs.
    Leaf(Leaf<'a>),
    /// Not there yet: the walk started loading what its next step reads.
    Wait,
    /// No leaf is left.
    End,
}

/// Where a walk stands.
#[derive(Clone, Copy, Debug)]
enum State<'a> {
    /// About to look up the tile `(ix, iy)` (a batch first starts loading its TILES entry).
    Seek,
    /// About to enter the tile `(ix, iy)`.
    Enter,
    /// In a non-empty tile whose block starts at word `at` of LEAVES (loading).
    Open(usize),
    /// Visiting the leaves of a tile.
    Leaves(Tile<'a>),
    End,
}

/// The leaves of one tile still ahead of the ray.
#[derive(Clone, Copy, Debug)]
struct Tile<'a> {
    block: Block<'a>,
    ray: CellRay,
    /// The next leaf to visit, and the parameter at which the ray enters it.
    leaf: usize,
    leaf_enter: f64,
    /// The parameter at which the ray leaves the tile's z range (or the tile).
    hi: f64,
}

/// The part `[lo, hi]` of the ray's parameter range `[t_enter, t_exit]` over a tile in which it
/// is within the tile's z range `[z0, z1]` (quantized levels, [`Block::z_range`]), or `None` if
/// the ray misses it: tested before the tile's block is parsed, as most tiles a primary ray
/// crosses are passed in front of or behind.
#[inline(always)]
pub(crate) fn z_overlap(s: &Setup, [z0, z1]: [u16; 2], t_enter: f64, t_exit: f64) -> Option<(f64, f64)> {
    let (ta, tb) = if s.up { (s.t_at(z0), s.t_at(z1)) } else { (s.t_at(z1), s.t_at(z0)) };
    let (lo, hi) = (higher(t_enter, ta), lower(t_exit, tb));
    (lo <= hi).then_some((lo, hi))
}

impl<'a> Tile<'a> {
    /// The leaves of `block` (the tile at `corner`) that the ray reaches over `[lo, hi]`, the part
    /// of its range over the tile that lies within the tile's z range ([`z_overlap`]).
    #[inline(always)]
    fn new(block: Block<'a>, corner: [f64; 2], g: &Grid, s: &Setup, lo: f64, hi: f64) -> Self {
        let bounds = block.bounds();
        let k = block.leaf_count();
        // The leaf holding the entry point: the leaves partition [bounds[0], bounds[K]] in order.
        // Going up, the first leaf whose top is not below it; going down, the last whose bottom
        // is not above it.
        let leaf = entry_leaf(&bounds[1..k], s.oq + lo * s.dq, s.up);
        let c = g.cells_per_unit;
        let ray = CellRay {
            o: [(s.o[0] - corner[0]) * c, (s.o[1] - corner[1]) * c],
            d: [s.d[0] * c, s.d[1] * c],
            margin: g.margin * c,
        };
        Tile { block, ray, leaf, leaf_enter: lo, hi }
    }

    /// The next leaf with refs, front to back, or `None` when the ray has left the tile's leaves.
    #[inline(always)]
    fn next(&mut self, s: &Setup, counter: &mut impl Counter) -> Option<Leaf<'a>> {
        let bounds = self.block.bounds();
        let k = self.block.leaf_count();
        loop {
            // `leaf == k` marks a finished tile (a valid leaf index is below k).
            let leaf = self.leaf;
            if leaf >= k {
                return None;
            }
            let last = if s.up { leaf + 1 == k } else { leaf == 0 };
            let exit_t =
                if last { self.hi } else { lower(s.t_at(bounds[if s.up { leaf + 1 } else { leaf }]), self.hi) };
            counter.leaf();
            let refs = self.block.leaf(leaf).filter(|r| !r.is_empty());
            let enter_t = self.leaf_enter;
            if last || exit_t >= self.hi {
                self.leaf = k;
            } else {
                self.leaf_enter = exit_t;
                self.leaf = if s.up { leaf + 1 } else { leaf - 1 };
            }
            if let Some(refs) = refs {
                let bytes = self.block.leaf_bytes(refs);
                return Some(Leaf { bytes, len: refs.len, enter_t, exit_t, ray: self.ray });
            }
        }
    }
}

/// The number of inner leaf boundaries `inner` (in order) below the quantized beam coordinate
/// `q`, or not above it when `!up`: the index of the leaf that holds `q` (going up, the first
/// whose top is not below it; going down, the last whose bottom is not above it).
///
/// A count rather than a binary search: the comparisons are independent, so they run side by
/// side (vectorized) instead of waiting on each other's loads, and a block has tens of leaves.
/// On boundaries in order the two agree; on a lying file's, any count is a valid leaf index.
#[inline(always)]
pub(crate) fn entry_leaf(inner: &[u16], q: f64, up: bool) -> usize {
    // The boundaries are integers, so `b < q` is `b < ⌈q⌉` and `b ≤ q` is `b < ⌊q⌋ + 1`, and
    // `limit` is that integer bound clamped to 0..=65536 (a NaN `q` gives 0).
    let whole = (q as u32).min(65_536);
    let limit = if up {
        whole + ((whole as f64) < q) as u32
    } else if q >= 0.0 {
        whole + 1
    } else {
        0
    };
    let Some(last) = limit.checked_sub(1) else { return 0 };
    // `b < limit` as `b ≤ limit − 1` in sixteen bits (every boundary is at most 65535).
    let last = last.min(65_535) as u16;
    // Summed in sixteen bits, so the sum vectorizes as the comparisons do (a block has at most
    // 4096 leaves, `formats/vlf.md` §5.6).
    inner.iter().fold(0u16, |n, &b| n.wrapping_add((b <= last) as u16)) as usize
}

/// The tile grid walk of one ray (Amanatides and Woo 1987): the tile it is in, the parameters
/// of the next tile boundary on each axis, and the steps between boundaries.
#[derive(Clone, Copy, Debug)]
struct Dda {
    ix: i64,
    iy: i64,
    step_x: i64,
    step_y: i64,
    next_x: f64,
    next_y: f64,
    delta_x: f64,
    delta_y: f64,
    /// The parameter range of the ray over the current tile (`t_exit` once [`Dda::enter`]ed).
    t_enter: f64,
    t_exit: f64,
    /// Tile visits left: each step moves one axis monotonically, so `2n + 1` visits cover any
    /// segment.
    visits_left: usize,
}

impl Dda {
    /// The walk of `s` from the tile holding its entry point.
    #[inline(always)]
    fn new(g: &Grid, s: &Setup) -> Self {
        let n = g.n as i64;
        let (w, r) = (g.tile_width, g.radius);
        // Tile coordinates of the entry point, clamped: the grown scene pokes out of the grid by
        // at most the margin, where no triangle lies.
        // (Truncation equals floor under the clamp to [0, n−1], without a libm call.)
        let cell = |v: f64| (((v + r) * g.inv_tile_width) as i64).clamp(0, n - 1);
        let ix = cell(s.o[0] + s.t0 * s.d[0]);
        let iy = cell(s.o[1] + s.t0 * s.d[1]);
        // Parameter of the next tile boundary on each axis, and the parameter step between them.
        // (One division per axis: rounding here is far below the margin, like the rest.)
        let axis = |i: i64, o: f64, d: f64| -> (i64, f64, f64) {
            let inv = 1.0 / d;
            if d > 0.0 {
                (1, ((i + 1) as f64 * w - r - o) * inv, w * inv)
            } else if d < 0.0 {
                (-1, (i as f64 * w - r - o) * inv, -w * inv)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (step_x, next_x, delta_x) = axis(ix, s.o[0], s.d[0]);
        let (step_y, next_y, delta_y) = axis(iy, s.o[1], s.d[1]);
        Dda {
            ix,
            iy,
            step_x,
            step_y,
            next_x,
            next_y,
            delta_x,
            delta_y,
            t_enter: s.t0,
            t_exit: s.t0,
            visits_left: 2 * g.n + 1,
        }
    }

    /// Enters the current tile: sets `t_exit`; `false` if the visits are used up (only a lying
    /// file's non-finite values get there).
    #[inline(always)]
    fn enter(&mut self, s: &Setup) -> bool {
        if self.visits_left == 0 {
            return false;
        }
        self.visits_left -= 1;
        self.t_exit = lower(lower(self.next_x, self.next_y), s.t1);
        true
    }

    /// The tile after the current one, if the ray goes on past this tile (it may lie outside the
    /// grid).
    #[inline(always)]
    fn ahead(&self, s: &Setup) -> Option<(i64, i64)> {
        if !(self.t_exit < s.t1) {
            return None;
        }
        Some(if self.next_x <= self.next_y {
            (self.ix + self.step_x, self.iy)
        } else {
            (self.ix, self.iy + self.step_y)
        })
    }

    /// Moves to the next tile along the ray; `false` at the end of the ray's segment or of the
    /// grid.
    #[inline(always)]
    fn leave(&mut self, g: &Grid, s: &Setup) -> bool {
        let n = g.n as i64;
        if self.t_exit >= s.t1 {
            return false;
        }
        // Only the coordinate that moves can leave the grid: both start inside it.
        if self.next_x <= self.next_y {
            self.ix += self.step_x;
            self.t_enter = self.next_x;
            self.next_x += self.delta_x;
            (0..n).contains(&self.ix)
        } else {
            self.iy += self.step_y;
            self.t_enter = self.next_y;
            self.next_y += self.delta_y;
            (0..n).contains(&self.iy)
        }
    }

    /// The corner `(x, y)` of the current tile in the direction's frame.
    #[inline(always)]
    fn corner(&self, g: &Grid) -> [f64; 2] {
        let (w, r) = (g.tile_width, g.radius);
        [-r + self.ix as f64 * w, -r + self.iy as f64 * w]
    }
}

/// The TILES and LEAVES of one direction: where a walk finds its tiles' blocks.
#[derive(Clone, Copy, Debug)]
struct Beam<'a> {
    tiles: &'a [u32],
    leaves: &'a [u64],
    /// The direction's first word in LEAVES, and its first entry in TILES.
    leaves_base: usize,
    tiles_of_dir: usize,
}

impl<'a> Beam<'a> {
    /// The beam of the ray `s`'s direction, or `None` if the file has none (a lying file).
    #[inline(always)]
    fn new(reader: &FieldReader<'a>, g: &Grid, s: &Setup) -> Option<Self> {
        let beam = reader.beams.get(s.dir)?;
        Some(Beam {
            tiles: reader.tiles,
            leaves: reader.leaves,
            leaves_base: beam.leaves_base as usize,
            tiles_of_dir: g.n * g.n * s.dir,
        })
    }

    /// The TILES entry of tile `(x, y)` (inside the grid) of the direction, if the file has it.
    #[inline(always)]
    fn entry(&self, g: &Grid, x: i64, y: i64) -> Option<u32> {
        self.tiles.get(self.tiles_of_dir + y as usize * g.n + x as usize).copied()
    }

    /// The word of LEAVES where the block of a non-empty tile's `entry` starts.
    #[inline(always)]
    fn block_at(&self, entry: u32) -> Option<usize> {
        (entry != EMPTY_TILE).then(|| self.leaves_base.wrapping_add(entry as usize))
    }

    /// The TILES entry of the tile `ahead`, if there is one and it is in the grid.
    #[inline(always)]
    fn ahead_entry(&self, g: &Grid, ahead: Option<(i64, i64)>) -> Option<u32> {
        let n = g.n as i64;
        let (x, y) = ahead?;
        if (0..n).contains(&x) && (0..n).contains(&y) { self.entry(g, x, y) } else { None }
    }

    /// Starts loading the block of the tile `ahead` (if it is in the grid and not empty).
    #[inline(always)]
    fn prefetch_block(&self, g: &Grid, ahead: Option<(i64, i64)>) {
        if let Some(word) = self.ahead_entry(g, ahead).and_then(|e| self.block_at(e)).and_then(|at| self.leaves.get(at))
        {
            prefetch(word);
        }
    }

    /// The leaves of the block at word `at` that the ray `s` reaches over the current tile of
    /// `dda`, or `None` if the block does not parse or the ray misses its z range.
    #[inline(always)]
    fn tile(&self, at: usize, g: &Grid, s: &Setup, dda: &Dda) -> Option<Tile<'a>> {
        let words = self.leaves.get(at..)?;
        let (lo, hi) = z_overlap(s, Block::z_range(words)?, dda.t_enter, dda.t_exit)?;
        Some(Tile::new(Block::parse(words)?, dda.corner(g), g, s, lo, hi))
    }
}

/// Runs the walk of the ray `s` through the field of `reader` to its end, handing each leaf with
/// refs to `visit` front to back, until `visit` returns `true`: the single-ray form of [`Walk`],
/// written as plain loops so that its state stays in registers. It sees the same tiles and leaves
/// in the same order as a [`Walk`], and counts the same work.
#[inline(always)]
pub(crate) fn walk_leaves<'a, C: Counter>(
    reader: &FieldReader<'a>,
    g: &Grid,
    s: &Setup,
    counter: &mut C,
    mut visit: impl FnMut(&Leaf<'a>, &mut C) -> bool,
) {
    let Some(beam) = Beam::new(reader, g, s) else { return };
    let mut dda = Dda::new(g, s);
    while dda.enter(s) {
        counter.cell();
        // Start loading the next tile's block while this one is visited.
        beam.prefetch_block(g, dda.ahead(s));
        if let Some(at) = beam.entry(g, dda.ix, dda.iy).and_then(|e| beam.block_at(e))
            && let Some(mut tile) = beam.tile(at, g, s, &dda)
        {
            while let Some(leaf) = tile.next(s, counter) {
                if visit(&leaf, counter) {
                    return;
                }
            }
        }
        if !dda.leave(g, s) {
            return;
        }
    }
}

/// A ray's walk through the field as a resumable cursor: the tiles its projection crosses and
/// their leaves, front to back, a step at a time ([`Walk::step`]), for the batches that advance
/// several rays in turn.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Walk<'a> {
    beam: Beam<'a>,
    dda: Dda,
    state: State<'a>,
}

impl<'a> Walk<'a> {
    /// The walk of the ray `s` through the field of `reader`, or `None` if the file has no
    /// beam for its direction (a lying file).
    #[inline(always)]
    pub(crate) fn new(reader: &FieldReader<'a>, g: &Grid, s: &Setup) -> Option<Self> {
        Some(Walk { beam: Beam::new(reader, g, s)?, dda: Dda::new(g, s), state: State::Seek })
    }

    /// One step: a leaf, or a move that started loading something the next step reads (the
    /// TILES entry's block, or a block's leaf): [`Step::Wait`], so that the caller can turn to
    /// other work while the load is under way.
    #[inline(always)]
    pub(crate) fn step(&mut self, g: &Grid, s: &Setup, counter: &mut impl Counter) -> Step<'a> {
        loop {
            match self.state {
                State::Seek => {
                    self.state = State::Enter;
                    if let Some(entry) =
                        self.beam.tiles.get(self.beam.tiles_of_dir + self.dda.iy as usize * g.n + self.dda.ix as usize)
                    {
                        prefetch(entry);
                    }
                }
                State::Enter => {
                    if !self.dda.enter(s) {
                        self.state = State::End;
                        return Step::End;
                    }
                    counter.cell();
                    // Start loading the next tile's block while this one is visited.
                    self.beam.prefetch_block(g, self.dda.ahead(s));
                    match self.beam.entry(g, self.dda.ix, self.dda.iy).and_then(|e| self.beam.block_at(e)) {
                        Some(at) => {
                            if let Some(word) = self.beam.leaves.get(at) {
                                prefetch(word);
                            }
                            self.state = State::Open(at);
                        }
                        None => {
                            if !self.leave_tile(g, s) {
                                return Step::End;
                            }
                            continue;
                        }
                    }
                }
                State::Open(at) => {
                    match self.beam.tile(at, g, s, &self.dda) {
                        Some(tile) => self.state = State::Leaves(tile),
                        None => {
                            if !self.leave_tile(g, s) {
                                return Step::End;
                            }
                        }
                    }
                    continue;
                }
                State::Leaves(ref mut tile) => match tile.next(s, counter) {
                    Some(leaf) => return Step::Leaf(leaf),
                    None => {
                        if !self.leave_tile(g, s) {
                            return Step::End;
                        }
                        continue;
                    }
                },
                State::End => return Step::End,
            }
            return Step::Wait;
        }
    }

    /// Moves to the next tile along the ray; `false` (and the walk ends) at the end of the ray's
    /// segment or of the grid.
    #[inline(always)]
    fn leave_tile(&mut self, g: &Grid, s: &Setup) -> bool {
        if self.dda.leave(g, s) {
            self.state = State::Seek;
            true
        } else {
            self.state = State::End;
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Setup, entry_leaf};

    /// A reversed segment is the same segment: its point at `t'` is the original's at `t1 − t'`,
    /// its beam coordinate runs the other way, and reversing twice gives the original back.
    #[test]
    fn a_reversed_segment_is_the_same_segment_from_its_far_end() {
        let s = Setup {
            dir: 3,
            o: [0.25, -0.5, -2.0],
            d: [0.1, 0.05, 1.0],
            t0: 0.5,
            t1: 3.5,
            oq: 100.0,
            dq: 400.0,
            inv_dq: 1.0 / 400.0,
            up: true,
        };
        let r = s.reversed();
        assert_eq!((r.dir, r.t0, r.t1, r.up), (3, 0.0, 3.0, false));
        for t in [0.0, 0.75, 1.5, 3.0] {
            let (a, b) = (s.t1 - t, t);
            for k in 0..3 {
                assert!((s.o[k] + a * s.d[k] - (r.o[k] + b * r.d[k])).abs() < 1e-12, "t' = {t}");
            }
            assert!((s.oq + a * s.dq - (r.oq + b * r.dq)).abs() < 1e-9);
        }
        let rr = r.reversed();
        assert_eq!((rr.t0, rr.t1, rr.up), (0.0, 3.0, true));
        assert!((0..3).all(|k| (rr.o[k] - (s.o[k] + s.t0 * s.d[k])).abs() < 1e-12));
        // An any-hit search walks the segment from its far end if it leaves the scene (ends
        // before `tmax`) and starts within 2²⁶ radii; otherwise forward, the first leaf put off.
        let (far, defer) = s.for_any_hit(10.0, 1.0);
        assert!(!defer && far.t1 == r.t1 && far.o == r.o && !far.up);
        let (near, defer) = s.for_any_hit(3.5, 1.0);
        assert!(defer && near.t0 == s.t0 && near.o == s.o && near.up);
        assert!(s.for_any_hit(10.0, 1e-8).1, "an origin 2·10⁸ radii out is walked forward");
    }

    /// [`entry_leaf`] is the binary search it replaces, on boundaries in order, for coordinates
    /// on, between, below and above them (and a NaN, which counts nothing).
    #[test]
    fn the_entry_leaf_is_the_partition_point() {
        let mut next = crate::test_rng::xorshift(0x9e37_79b9_7f4a_7c15);
        for _ in 0..20_000 {
            let k = (next() % 40) as usize;
            let mut inner: Vec<u16> = (0..k).map(|_| next() as u16 % 200).collect();
            inner.sort_unstable();
            let pick = next() % 4;
            let q = match pick {
                0 => inner.get((next() as usize) % (k + 1)).map_or(0.0, |&b| b as f64),
                1 => (next() % 220) as f64 + (next() % 1000) as f64 / 1000.0,
                2 => -((next() % 3) as f64) - 0.25 * (next() % 2) as f64,
                _ => [f64::INFINITY, 1e12, 65_535.5, 65_536.0, -0.0, 0.5][(next() % 6) as usize],
            };
            assert_eq!(entry_leaf(&inner, q, true), inner.partition_point(|&b| (b as f64) < q), "{inner:?} {q}");
            assert_eq!(entry_leaf(&inner, q, false), inner.partition_point(|&b| (b as f64) <= q), "{inner:?} {q}");
        }
        assert_eq!(entry_leaf(&[1, 2, 3], f64::NAN, true), 0);
        assert_eq!(entry_leaf(&[1, 2, 3], f64::NAN, false), 0);
    }
}
