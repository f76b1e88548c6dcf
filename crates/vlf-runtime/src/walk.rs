//! Steps 3 and 4 of the query ([`crate::query`]) as a cursor: the tiles a ray's projection
//! crosses, front to back (Amanatides and Woo 1987 in the tile grid), and in each the leaves of
//! its block (`formats/vlf.md` §5.6) that the ray's z range passes through, in ray order.
//!
//! The walk is a resumable state machine rather than a loop, so that one ray can be advanced a
//! step at a time: a single query runs it to the next leaf at once ([`Walk::next_leaf`]), while
//! a batch ([`crate::batch`]) advances several rays in turn and starts loading what each one
//! needs next before coming back to it, so that their cache misses overlap. Both see the same
//! leaves in the same order, so they give the same answers.
//!
//! Geometry here is in f64: its rounding stays far below the margin `μ` by which the baker grew
//! every footprint, z range and box (`formats/vlf.md` §6.2). Every index read from the file is
//! bounds-checked where it is used: a lying file yields wrong answers at worst, never a panic or
//! unbounded work (a ray visits at most `2n + 1` tiles and, in each, at most its `K` leaves).

// Comparisons are written `!(a <= b)` on purpose: a NaN (from a lying file) takes the reject
// branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::filter::{Limits, Passing, limits};
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

impl Setup {
    /// The ray parameter at which the beam coordinate reaches quantized `level`.
    #[inline(always)]
    fn t_at(&self, level: u16) -> f64 {
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
    /// The limits of the box of cells the ray passes over `[t_a, t_b]`, grown by the margin.
    #[inline(always)]
    fn limits(&self, t_a: f64, t_b: f64) -> Limits {
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

impl<'a> Tile<'a> {
    /// The leaves of `block` (the tile at `corner`) that the ray's parameter range
    /// `[t_enter, t_exit]` reaches, or `None` if it misses the tile's z range.
    #[inline(always)]
    fn new(block: Block<'a>, corner: [f64; 2], g: &Grid, s: &Setup, t_enter: f64, t_exit: f64) -> Option<Self> {
        let bounds = block.bounds();
        let k = block.leaf_count();
        // The parameter range over which the ray is within the tile's z range.
        let (ta, tb) =
            if s.up { (s.t_at(bounds[0]), s.t_at(bounds[k])) } else { (s.t_at(bounds[k]), s.t_at(bounds[0])) };
        let lo = higher(t_enter, ta);
        let hi = lower(t_exit, tb);
        if !(lo <= hi) {
            return None;
        }
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
        Some(Tile { block, ray, leaf, leaf_enter: lo, hi })
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
            // Start loading the next leaf's boxes while this one is tested.
            if !last {
                if let Some(next) = self.block.leaf(if s.up { leaf + 1 } else { leaf - 1 }) {
                    if let Some(b) = self.block.leaf_bytes(next).first() {
                        prefetch(b);
                    }
                }
            }
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

/// A ray's walk through the field: the tiles its projection crosses and their leaves, front to
/// back.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Walk<'a> {
    tiles: &'a [u32],
    leaves: &'a [u64],
    /// The direction's first word in LEAVES, and its first entry in TILES.
    leaves_base: usize,
    tiles_of_dir: usize,
    /// The current tile, the parameters of the next tile boundary on each axis, and the steps
    /// between boundaries.
    ix: i64,
    iy: i64,
    step_x: i64,
    step_y: i64,
    next_x: f64,
    next_y: f64,
    delta_x: f64,
    delta_y: f64,
    /// The parameter range of the ray over the current tile.
    t_enter: f64,
    t_exit: f64,
    /// Tile visits left: each step moves one axis monotonically, so `2n + 1` visits cover any
    /// segment.
    visits_left: usize,
    state: State<'a>,
}

impl<'a> Walk<'a> {
    /// The walk of the ray `s` through the field of `reader`, or `None` if the file has no
    /// beam for its direction (a lying file).
    #[inline(always)]
    pub(crate) fn new(reader: &FieldReader<'a>, g: &Grid, s: &Setup) -> Option<Self> {
        let beam = reader.beams.get(s.dir)?;
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
        Some(Walk {
            tiles: reader.tiles,
            leaves: reader.leaves,
            leaves_base: beam.leaves_base as usize,
            tiles_of_dir: g.n * g.n * s.dir,
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
            state: State::Seek,
        })
    }

    /// The next leaf with refs along the ray, or `None` at the end of the walk.
    #[inline(always)]
    pub(crate) fn next_leaf(&mut self, g: &Grid, s: &Setup, counter: &mut impl Counter) -> Option<Leaf<'a>> {
        match self.advance::<false>(g, s, counter) {
            Step::Leaf(leaf) => Some(leaf),
            Step::Wait | Step::End => None,
        }
    }

    /// One step: a leaf, or a move that started loading something the next step reads (the
    /// TILES entry's block, or a block's leaf): [`Step::Wait`], so that the caller can turn to
    /// other work while the load is under way.
    #[inline(always)]
    pub(crate) fn step(&mut self, g: &Grid, s: &Setup, counter: &mut impl Counter) -> Step<'a> {
        self.advance::<true>(g, s, counter)
    }

    /// The TILES entry of tile `(x, y)` of the ray's direction, if the file has it.
    #[inline(always)]
    fn entry(&self, g: &Grid, x: i64, y: i64) -> Option<u32> {
        self.tiles.get(self.tiles_of_dir + y as usize * g.n + x as usize).copied()
    }

    /// Moves on to the next leaf with refs, or the end; with `PAUSE`, returns [`Step::Wait`]
    /// after each move that started a load.
    #[inline(always)]
    fn advance<const PAUSE: bool>(&mut self, g: &Grid, s: &Setup, counter: &mut impl Counter) -> Step<'a> {
        loop {
            match self.state {
                State::Seek => {
                    self.state = State::Enter;
                    if !PAUSE {
                        continue;
                    }
                    if let Some(entry) = self.tiles.get(self.tiles_of_dir + self.iy as usize * g.n + self.ix as usize) {
                        prefetch(entry);
                    }
                }
                State::Enter => {
                    if self.visits_left == 0 {
                        self.state = State::End;
                        return Step::End;
                    }
                    self.visits_left -= 1;
                    self.t_exit = lower(lower(self.next_x, self.next_y), s.t1);
                    counter.cell();
                    let n = g.n as i64;
                    // Start loading the next tile's block while this one is visited.
                    if self.t_exit < s.t1 {
                        let (nx, ny) = if self.next_x <= self.next_y {
                            (self.ix + self.step_x, self.iy)
                        } else {
                            (self.ix, self.iy + self.step_y)
                        };
                        if (0..n).contains(&nx) && (0..n).contains(&ny) {
                            if let Some(next) = self.entry(g, nx, ny) {
                                if let Some(word) = self.leaves.get(self.leaves_base.wrapping_add(next as usize)) {
                                    prefetch(word);
                                }
                            }
                        }
                    }
                    match self.entry(g, self.ix, self.iy) {
                        Some(entry) if entry != EMPTY_TILE => {
                            let at = self.leaves_base.wrapping_add(entry as usize);
                            if PAUSE {
                                if let Some(word) = self.leaves.get(at) {
                                    prefetch(word);
                                }
                            }
                            self.state = State::Open(at);
                        }
                        _ => {
                            if !self.leave_tile(g, s) {
                                return Step::End;
                            }
                            continue;
                        }
                    }
                }
                State::Open(at) => {
                    let (w, r) = (g.tile_width, g.radius);
                    let corner = [-r + self.ix as f64 * w, -r + self.iy as f64 * w];
                    let tile = self
                        .leaves
                        .get(at..)
                        .and_then(Block::parse)
                        .and_then(|block| Tile::new(block, corner, g, s, self.t_enter, self.t_exit));
                    match tile {
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
            if PAUSE {
                return Step::Wait;
            }
        }
    }

    /// Moves to the next tile along the ray; `false` (and the walk ends) at the end of the ray's
    /// segment or of the grid.
    #[inline(always)]
    fn leave_tile(&mut self, g: &Grid, s: &Setup) -> bool {
        let n = g.n as i64;
        if self.t_exit >= s.t1 {
            self.state = State::End;
            return false;
        }
        if self.next_x <= self.next_y {
            self.ix += self.step_x;
            self.t_enter = self.next_x;
            self.next_x += self.delta_x;
        } else {
            self.iy += self.step_y;
            self.t_enter = self.next_y;
            self.next_y += self.delta_y;
        }
        if !(0..n).contains(&self.ix) || !(0..n).contains(&self.iy) {
            self.state = State::End;
            return false;
        }
        self.state = State::Seek;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::entry_leaf;

    /// [`entry_leaf`] is the binary search it replaces, on boundaries in order, for coordinates
    /// on, between, below and above them (and a NaN, which counts nothing).
    #[test]
    fn the_entry_leaf_is_the_partition_point() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
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
