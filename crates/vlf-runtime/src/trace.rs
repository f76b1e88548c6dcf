//! The single-ray walk (steps 3 to 5 of [`crate::query`]) as one loop nest: the tiles a ray's
//! projection crosses, front to back (Amanatides and Woo 1987 in the tile grid); in each the leaves
//! of its block (`formats/vlf.md` §5.6) that the ray's z range passes through, in ray order; in
//! each leaf the refs whose boxes meet the ray's box, collected into a short list apart from the
//! kernel (so that the filter's loop and the kernel's each keep their values in registers), each
//! one's triangle started loading as soon as it passes, then tested four at a time by the leaf
//! kernel ([`vlf_geom::TriRay::closest4`], [`vlf_geom::TriRay::any4`]). The search stops once the best hit
//! lies within the part of the ray already searched (closest hit) or at the first hit (any hit).
//! An any-hit search walks a segment that leaves the scene from that far end, and puts off the
//! leaf where any other segment starts until the rest is searched ([`OriginLeaf`]): a shadow ray's
//! occluder is seldom in the surface it leaves (`crate::walk::Setup::for_any_hit`).
//!
//! It visits the tiles and leaves that [`crate::walk`]'s parts visit, in the same order, but is
//! written out on its own, without closures: it is compiled inside the queries built for AVX2 and
//! AVX-512 (a closure's body, if not inlined, would be compiled without those instructions), and
//! the parts assembled measured 5–20% slower (`docs/benchmarks/where-the-time-goes.md`).
//!
//! Geometry here is in f64: its rounding stays far below the margin `μ` by which the baker grew
//! every footprint, z range and box (`formats/vlf.md` §6.2). Every index read from the file is
//! bounds-checked where it is used: a lying file yields wrong answers at worst, never a panic or
//! unbounded work (a ray visits at most `2n + 1` tiles and, in each, at most its `K` leaves).

// Comparisons are written `!(a <= b)` on purpose: a NaN (from a lying file) takes the reject
// branch.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::filter::{Limits, pass_mask, segment_limits};
use crate::prefetch::{prefetch, prefetch_lines};
use crate::walk::{Grid, Setup, entry_leaf, lower, z_overlap};
use vlf_format::block::{Block, header_bytes};
use vlf_format::{EMPTY_TILE, FieldReader};
use vlf_geom::kernel::FILLER;
use vlf_geom::{Closest, Counter, Hit, Isa, Tri, TriRay, Triangles};

/// What the walk does with the triangles that pass a leaf's box test.
pub(crate) trait Search<'t> {
    /// Where the triangles are.
    type Tris: Triangles + ?Sized + 't;
    /// The triangles.
    fn tris(&self) -> &'t Self::Tris;
    /// Tests the first `n` of four triangles; returns whether the search is over.
    fn test4<C: Counter>(&mut self, ids: [u32; 4], tris: [&'t Tri; 4], n: usize, counter: &mut C) -> bool;
    /// The end of the interval still searched.
    fn limit(&self) -> f64;
    /// Whether the search is over once the ray has searched up to `exit`.
    fn done(&self, exit: f64) -> bool;
    /// Whether the leaf where the ray starts is searched last ([`OriginLeaf`]).
    const DEFER_ORIGIN: bool;
}

/// The closest-hit search.
pub(crate) struct ClosestSearch<'t, I, T: ?Sized> {
    pub(crate) isa: I,
    pub(crate) ray: TriRay,
    pub(crate) tris: &'t T,
    pub(crate) best: Closest,
}

impl<'t, I: Isa, T: Triangles + ?Sized + 't> Search<'t> for ClosestSearch<'t, I, T> {
    type Tris = T;
    #[inline(always)]
    fn tris(&self) -> &'t T {
        self.tris
    }
    #[inline(always)]
    fn test4<C: Counter>(&mut self, ids: [u32; 4], tris: [&'t Tri; 4], n: usize, counter: &mut C) -> bool {
        for _ in 0..n {
            counter.test();
        }
        self.ray.closest4(self.isa, ids, tris, n, &mut self.best);
        false
    }
    #[inline(always)]
    fn limit(&self) -> f64 {
        self.best.tmax as f64
    }
    #[inline(always)]
    fn done(&self, exit: f64) -> bool {
        self.best.hit.is_some() && (self.best.tmax as f64) <= exit
    }
    const DEFER_ORIGIN: bool = false;
}

/// The any-hit search; with `DEFER`, the leaf where the walk starts is searched last
/// ([`OriginLeaf`]).
pub(crate) struct AnySearch<'t, I, T: ?Sized, const DEFER: bool> {
    pub(crate) isa: I,
    pub(crate) ray: TriRay,
    pub(crate) tris: &'t T,
    pub(crate) found: Option<Hit>,
}

impl<'t, I: Isa, T: Triangles + ?Sized + 't, const DEFER: bool> Search<'t> for AnySearch<'t, I, T, DEFER> {
    type Tris = T;
    #[inline(always)]
    fn tris(&self) -> &'t T {
        self.tris
    }
    #[inline(always)]
    fn test4<C: Counter>(&mut self, ids: [u32; 4], tris: [&'t Tri; 4], n: usize, counter: &mut C) -> bool {
        let found = self.ray.any4(self.isa, ids, tris, n);
        for _ in 0..found.map_or(n, |(i, _)| i + 1) {
            counter.test();
        }
        self.found = found.map(|(_, h)| h);
        self.found.is_some()
    }
    #[inline(always)]
    fn limit(&self) -> f64 {
        f64::INFINITY
    }
    #[inline(always)]
    fn done(&self, _exit: f64) -> bool {
        self.found.is_some()
    }
    const DEFER_ORIGIN: bool = DEFER;
}

/// Cache lines of refs started loading when a ray enters a tile, from its entry leaf on.
const PREFETCH_LINES: usize = 8;

/// Cache lines of a block started loading as soon as its tile's entry is read, before its header
/// is: the header and the first leaves' refs arrive together instead of one after the other
/// (incoherent rays 6–12% faster, `docs/benchmarks/where-the-time-goes.md`).
const BLOCK_LINES: usize = 4;

/// Starts loading the first [`BLOCK_LINES`] cache lines of the block that starts at `words[0]`.
#[inline(always)]
fn prefetch_block(words: &[u64]) {
    if let Some(w) = words.first() {
        prefetch_lines(w, BLOCK_LINES, 64);
    }
}

/// Up to four triangles waiting for the kernel.
struct Pending<'t> {
    ids: [u32; 4],
    tris: [&'t Tri; 4],
    n: usize,
}

/// Walks the ray `s` through the tiles and leaves of the field of `reader` (whose grid is `g`)
/// front to back, handing the triangles whose boxes meet it to `search` until the search is over.
#[inline(always)]
pub(crate) fn trace<'t, C: Counter, S: Search<'t>>(
    reader: &FieldReader<'_>,
    g: &Grid,
    s: &Setup,
    search: &mut S,
    counter: &mut C,
) {
    let Some(beam) = reader.beams.get(s.dir) else { return };
    let n = g.n;
    let ni = n as i64;
    let Some(tiles) = reader.tiles.get(n * n * s.dir..n * n * (s.dir + 1)) else { return };
    let lbase = beam.leaves_base as usize;
    let (w, r) = (g.tile_width, g.radius);
    // Tile coordinates of the entry point, clamped: the grown scene pokes out of the grid by
    // at most the margin, where no triangle lies. (Truncation is floor under the clamp.)
    let cell = |v: f64| (((v + r) * g.inv_tile_width) as i64).clamp(0, ni - 1);
    let mut ix = cell(s.o[0] + s.t0 * s.d[0]);
    let mut iy = cell(s.o[1] + s.t0 * s.d[1]);
    // The next tile boundary on each axis and the step between boundaries (Amanatides and
    // Woo): one division per axis.
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
    let (step_x, mut next_x, delta_x) = axis(ix, s.o[0], s.d[0]);
    let (step_y, mut next_y, delta_y) = axis(iy, s.o[1], s.d[1]);
    // The column and the row past which a step leaves the grid: the tile indices start within
    // it and each moves one way only. (An axis the ray does not move along is never stepped:
    // its next boundary is infinite, so that crossing it first means the segment ends first.)
    let last_x = if step_x > 0 { ni - 1 } else { 0 };
    let last_y = if step_y > 0 { ni - 1 } else { 0 };
    let mut t_enter = s.t0;
    // Each step moves one axis monotonically, so 2n + 1 visits cover any segment.
    let mut visits = 2 * n + 1;
    let cpu = g.cells_per_unit;
    let margin = g.margin * cpu;
    let (dcx, dcy) = (s.d[0] * cpu, s.d[1] * cpu);
    let tris = search.tris();
    let mut origin: Option<OriginLeaf<'_>> = None;
    let mut passing = Candidates::new();
    // The current tile's TILES entry: the first tile's read here (and its block started, as no
    // tile before it did), each next one's carried over from the look-ahead of the tile before.
    let mut entry = tiles.get(iy as usize * n + ix as usize).copied().unwrap_or(EMPTY_TILE);
    if entry != EMPTY_TILE
        && let Some(words) = reader.leaves.get(lbase.wrapping_add(entry as usize)..)
    {
        prefetch_block(words);
    }
    let over = 'walk: {
        while visits > 0 {
            visits -= 1;
            counter.cell();
            let t_exit = lower(lower(next_x, next_y), s.t1);
            let more = t_exit < s.t1;
            // Which axis the ray crosses next: one comparison, for the look-ahead and the step.
            let x_first = next_x <= next_y;
            let (nx, ny) = if x_first { (ix + step_x, iy) } else { (ix, iy + step_y) };
            let ahead = more && if x_first { ix != last_x } else { iy != last_y };
            let next_entry = if ahead {
                tiles.get(ny as usize * n + nx as usize).copied().unwrap_or(EMPTY_TILE)
            } else {
                EMPTY_TILE
            };
            // Start loading the block of the tile after this one, while this one is visited.
            if next_entry != EMPTY_TILE
                && let Some(words) = reader.leaves.get(lbase.wrapping_add(next_entry as usize)..)
            {
                prefetch_block(words);
            }
            if entry != EMPTY_TILE
                && let Some(words) = reader.leaves.get(lbase.wrapping_add(entry as usize)..)
                && let Some(z) = Block::z_range(words)
                && let Some((lo, hi)) = z_overlap(s, z, t_enter, t_exit)
                && let Some(block) = Block::parse(words)
            {
                let corner = [-r + ix as f64 * w, -r + iy as f64 * w];
                let ray =
                    CellRay { o: [(s.o[0] - corner[0]) * cpu, (s.o[1] - corner[1]) * cpu], d: [dcx, dcy], margin };
                if visit_tile(&block, s, &ray, lo, hi, tris, search, counter, &mut origin, &mut passing) {
                    break 'walk true;
                }
            }
            if !ahead {
                break 'walk false;
            }
            if x_first {
                t_enter = next_x;
                next_x += delta_x;
            } else {
                t_enter = next_y;
                next_y += delta_y;
            }
            (ix, iy) = (nx, ny);
            entry = next_entry;
        }
        false
    };
    if !over && let Some(d) = origin {
        visit_leaf(&d.block, d.at, d.c, d.limits, tris, search, counter, &mut passing);
    }
}

/// The leaf where a ray starts, which an any-hit search tests last.
///
/// A shadow or secondary ray starts on a surface, and the leaf it starts in holds that surface's
/// triangles around the origin: their boxes meet the ray's box over the leaf (which starts at the
/// origin), yet the ray leaves them behind (their hits, if any, lie before `tmin`). On the dragon's
/// shadow rays this leaf took 11.4 of a ray's 25.8 triangle tests, and the occluder lay in a later
/// leaf. An any-hit search may return any hit, so searching this leaf after the rest of the ray
/// changes which hit is found, never whether one is: it is tested only if nothing else is hit.
///
/// It is the first leaf with refs whose part of the ray begins at the ray's start `t0`: the parts
/// only move forward, so no later leaf begins there unless every leaf before it, this one among
/// them, is empty in `t`.
struct OriginLeaf<'r> {
    /// Its refs start at byte `at` of `block`, `c` of them; the ray's box over it is `limits`.
    block: Block<'r>,
    at: usize,
    c: usize,
    limits: Limits,
}

/// The ray over one tile in its box cells: at parameter `t` it is at `o + t·d` cells from the
/// tile's corner; `margin` is the margin `μ` in cells.
#[derive(Clone, Copy)]
struct CellRay {
    o: [f64; 2],
    d: [f64; 2],
    margin: f64,
}

impl CellRay {
    /// The limits of the box of cells the ray passes over `[ta, tb]`, grown by the margin.
    #[inline(always)]
    fn limits(&self, ta: f64, tb: f64) -> Limits {
        let (o, d) = (self.o, self.d);
        segment_limits([o[0] + ta * d[0], o[1] + ta * d[1]], [o[0] + tb * d[0], o[1] + tb * d[1]], self.margin)
    }
}

/// Visits the leaves of `block` that the ray `s` passes through over `[lo, hi]` (the part of its
/// range over the tile that lies within the tile's z range, not empty: the caller checked it
/// with [`z_overlap`] before parsing the block), front to back; returns whether the search is
/// over.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn visit_tile<'t, 'r, C: Counter, S: Search<'t>>(
    block: &Block<'r>,
    s: &Setup,
    ray: &CellRay,
    lo: f64,
    hi: f64,
    tris: &'t S::Tris,
    search: &mut S,
    counter: &mut C,
    origin: &mut Option<OriginLeaf<'r>>,
    passing: &mut Candidates,
) -> bool {
    let bounds = block.bounds();
    let ends = block.ends();
    let k = block.leaf_count();
    let m = block.ref_count();
    // The leaf holding the entry point; then the next one along the ray, until it leaves.
    let mut leaf = entry_leaf(&bounds[1..k], s.oq + lo * s.dq, s.up);
    let mut enter = lo;
    let hdr = header_bytes(k);
    {
        // Start loading the refs of the entry leaf and of the leaves after it, in the ray's
        // order: on a field larger than the cache, they are misses to memory that would
        // otherwise come one after the other.
        let lines = PREFETCH_LINES;
        let bytes = block.bytes();
        let start = hdr + 8 * if leaf == 0 { 0 } else { ends[leaf - 1] as usize };
        let end = hdr + 8 * ends[leaf] as usize;
        let (at, step) = if s.up { (start, 64) } else { (end.wrapping_sub(1), -64) };
        if let Some(b) = bytes.get(at) {
            prefetch_lines(b, lines, step);
        }
    }
    loop {
        let (bound, last) = if s.up { (leaf + 1, leaf + 1 >= k) } else { (leaf, leaf == 0) };
        let exit = if last { hi } else { lower(s.t_at(bounds[bound]), hi) };
        counter.leaf();
        let start = if leaf == 0 { 0 } else { ends[leaf - 1] as usize };
        let end = ends[leaf] as usize;
        if start < end && end <= m {
            let limits = ray.limits(enter, lower(exit, search.limit()));
            // The leaf the ray starts in is put off (`OriginLeaf`).
            if S::DEFER_ORIGIN && origin.is_none() && enter == s.t0 {
                *origin = Some(OriginLeaf { block: *block, at: hdr + 8 * start, c: end - start, limits });
            } else if visit_leaf(block, hdr + 8 * start, end - start, limits, tris, search, counter, passing)
                || search.done(exit)
            {
                return true;
            }
        }
        if last || exit >= hi {
            return false;
        }
        enter = exit;
        leaf = if s.up { leaf + 1 } else { leaf - 1 };
    }
}

/// Tests the `c` refs of the leaf whose arrays start at byte `at` of `block`: those whose boxes
/// pass `limits` go to the kernel four at a time. Returns whether the search is over.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn visit_leaf<'t, C: Counter, S: Search<'t>>(
    block: &Block<'_>,
    at: usize,
    c: usize,
    limits: Limits,
    tris: &'t S::Tris,
    search: &mut S,
    counter: &mut C,
    passing: &mut Candidates,
) -> bool {
    let bytes = block.bytes();
    // The ids: quarter `at / 4 + c + i` (the arrays start on a multiple of 4; `Block::parse`
    // checked that the leaf's `8c` bytes lie within the section).
    let Some(ids) = block.quarters().get(at / 4 + c..at / 4 + 2 * c) else { return false };
    let mut n = 0;
    let mut g = 0;
    while g < c {
        // The box test, sixteen refs per step, into a list of ids (in a loop of its own, apart
        // from the kernel, so that both keep their values in registers).
        let mut mask = pass_mask(&lanes(bytes, at + g, c), limits);
        if c - g < 16 {
            mask &= (1 << (c - g)) - 1;
        }
        while mask != 0 {
            let i = g + mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if let Some(&id) = ids.get(i) {
                n = passing.push(n, id);
                // Start loading its triangle as soon as it is known to pass.
                if let Some(t) = tris.vertices(id) {
                    prefetch(t);
                }
            }
        }
        g += 16;
        if n > CANDIDATES - 16 || g >= c {
            if test_all(passing.first(n), tris, search, counter) {
                return true;
            }
            n = 0;
        }
    }
    false
}

/// Tests the triangles `ids`, four at a time; returns whether the search is over.
#[inline(always)]
fn test_all<'t, C: Counter, S: Search<'t>>(ids: &[u32], tris: &'t S::Tris, search: &mut S, counter: &mut C) -> bool {
    let mut p = Pending { ids: [0; 4], tris: [&FILLER; 4], n: 0 };
    for &id in ids {
        let Some(tri) = tris.vertices(id) else { continue };
        p.ids[p.n] = id;
        p.tris[p.n] = tri;
        p.n += 1;
        if p.n == 4 {
            if search.test4(p.ids, p.tris, 4, counter) {
                return true;
            }
            p.n = 0;
        }
    }
    p.n > 0 && search.test4(p.ids, p.tris, p.n, counter)
}

/// The most passing refs a leaf hands to the kernel at once (a power of two).
const CANDIDATES: usize = 64;

/// Room for the short list of a leaf's passing triangle ids; its length is the caller's, kept
/// apart. Made once per ray and reused by every leaf: made per leaf, the array (uninitialised,
/// then) and a length of 0 held together were compiled into a store of zeros over the whole,
/// 256 bytes per leaf, and the length lived in memory.
struct Candidates {
    ids: [u32; CANDIDATES],
}

impl Candidates {
    #[inline(always)]
    fn new() -> Self {
        Candidates { ids: [0; CANDIDATES] }
    }

    /// Writes `id` after the first `len` ids; returns the new length. Callers empty the list
    /// while it has room for sixteen more and push at most sixteen between; past the capacity
    /// the last entry is overwritten (a wrong but harmless list, never a write out of bounds).
    #[inline(always)]
    fn push(&mut self, len: usize, id: u32) -> usize {
        let at = len.min(CANDIDATES - 1);
        self.ids[at] = id;
        at + 1
    }

    /// The first `len` ids (at most the capacity).
    #[inline(always)]
    fn first(&self, len: usize) -> &[u32] {
        &self.ids[..len.min(CANDIDATES)]
    }
}

/// Sixteen bytes of each of the four box arrays of a leaf of `c` refs whose arrays start at byte
/// `at` of `bytes`, from the ref at `at` on; 255 (a box no ray box passes) past the end of `bytes`.
/// Bytes past the leaf's refs are whatever follows; the caller masks them.
#[inline(always)]
fn lanes(bytes: &[u8], at: usize, c: usize) -> [[u8; 16]; 4] {
    match bytes.get(at..at + 3 * c + 16) {
        // One bounds check for the four arrays.
        Some(w) => std::array::from_fn(|a| w[a * c..a * c + 16].try_into().expect("16 bytes")),
        None => std::array::from_fn(|a| {
            let mut lane = [255u8; 16];
            let tail = bytes.get(at + a * c..).unwrap_or(&[]);
            let n = tail.len().min(16);
            lane[..n].copy_from_slice(&tail[..n]);
            lane
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list holds what was pushed, in order, up to its capacity; past it, the last entry is
    /// overwritten and the length stays at the capacity.
    #[test]
    fn candidates_keep_what_was_pushed_and_stay_within_their_room() {
        let mut list = Candidates::new();
        let mut n = 0;
        for id in 0..CANDIDATES as u32 {
            n = list.push(n, id * 3);
        }
        assert_eq!(n, CANDIDATES);
        assert_eq!(list.first(n), (0..CANDIDATES as u32).map(|id| id * 3).collect::<Vec<_>>());
        n = list.push(n, 7);
        assert_eq!(n, CANDIDATES);
        assert_eq!(list.first(n)[CANDIDATES - 1], 7);
        assert_eq!(list.first(usize::MAX).len(), CANDIDATES);
        let n = list.push(0, 11);
        assert_eq!(list.first(n), [11]);
    }
}
