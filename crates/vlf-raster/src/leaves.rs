//! Where a tile's leaves go (paper §7: "a better split heuristic than the mid-point"): the tile's
//! z range is cut into consecutive slabs by a one-dimensional surface-area heuristic over the z
//! ranges of the triangles in it (`formats/vlf.md` §6.3).
//!
//! A ray walks a tile's leaves in order along the beam and stops once it has a hit within the part
//! already searched, so a leaf's expected cost is roughly the chance that a ray reaches it (its
//! share of the tile's length) times what its refs cost. A split at `s` of a range `[a, b]` whose
//! refs cost `W` costs `C + ((s − a)·W_a + (b − s)·W_b) / (b − a)` triangle tests, against `W`
//! for a single leaf, where `W_a` and `W_b` sum the costs of the refs that meet each side (a ref
//! straddling `s` is in both) and `C` ([`leaf_cost`]) is what visiting one more leaf costs.
//!
//! A ref costs a ray that reaches it its share of a sixteen-ref box test plus, if its box passes
//! that test, one triangle test ([`ref_weight`]): a triangle whose box covers the whole tile is
//! tested by nearly every ray, one that covers a corner by few. So tiles of triangles small
//! against the tile get long leaves of many cheap refs, and tiles of large triangles short ones.
//!
//! The best split is taken while it is cheaper, so dense parts get small leaves, empty gaps become
//! empty leaves of no refs, and refs that all overlap (coincident triangles) stay in one leaf
//! instead of being copied into many. The old mid-point BSP copied a pile of coincident triangles
//! into every one of its `2^D` leaves.

use vlf_format::block::BOX_CELLS;

/// Default target of triangles per BSP leaf.
pub const DEFAULT_LEAF_SIZE: u32 = 4;
/// Default largest BSP depth.
pub const DEFAULT_MAX_DEPTH: u32 = 8;

/// How a tile's z range is cut into leaves (`formats/vlf.md` §6.3): a leaf of at most
/// `leaf_size` refs is not split, and splits go at most `max_depth` deep (a tile has at most
/// `2^max_depth` leaves). `max_depth = 0` gives the paper's "linear tiles", one leaf each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthPolicy {
    pub leaf_size: u32,
    pub max_depth: u32,
}

impl Default for DepthPolicy {
    fn default() -> Self {
        DepthPolicy { leaf_size: DEFAULT_LEAF_SIZE, max_depth: DEFAULT_MAX_DEPTH }
    }
}

/// The cost of visiting a leaf, in triangle tests, on grids coarser than [`FINE_TILES`]: a leaf
/// visit finds the leaf, computes the ray's box over it and starts its box tests, and ends a ray's
/// search only at its far side. [`RAY_CELLS`] was chosen with it by measuring bakes of the random
/// 100K scene and the dragon (`docs/benchmarks/parameters.md`, "Leaves weighted by their boxes");
/// the cost itself was raised from 1.5 to 2.5 in baker revision 6 by a sweep over five scenes
/// ("Leaf cost 2.5"): fields 3–21% smaller at the same parameters, rays as fast within noise (1M
/// density inside rays 6% slower), which lets the 1M random scene of fixed size reach finer tiles
/// within its budget.
pub const LEAF_COST: f64 = 2.5;

/// Grids of at least this many tiles per side, on lattices of at least [`FINE_LATTICE`]
/// segments, take [`FINE_LEAF_COST`].
pub const FINE_TILES: u32 = 128;

/// The fewest lattice segments (`N = 4`: 33 directions) on which fine grids take
/// [`FINE_LEAF_COST`].
pub const FINE_LATTICE: u32 = 4;

/// The cost of visiting a leaf on fine grids of many directions (baker revision 10). Measured
/// (`docs/benchmarks/parameters.md`, "Leaf cost 4 on 128² tiles of many directions"): on the
/// dragon's 128² tiles at 51 and 73 directions it makes fields 10% smaller with rays as fast or
/// faster, and the dragon's 73 × 128² field then fits its 1 KiB per triangle. At 9 directions (the
/// 1M random scene of fixed size, 128² tiles) the field was 18% smaller but its outside view
/// 6–19% slower: a ray further from its direction widens its box over a longer leaf. On 64²
/// tiles it saved 2–3% and cost the random scenes' rays up to 13%.
pub const FINE_LEAF_COST: f64 = 4.0;

/// The cost of visiting a leaf on a grid of `tiles` per side in a field of lattice size
/// `lattice_n`: [`FINE_LEAF_COST`] from [`FINE_TILES`] tiles and [`FINE_LATTICE`] segments up,
/// [`LEAF_COST`] otherwise.
pub fn leaf_cost(tiles: u32, lattice_n: u32) -> f64 {
    if tiles >= FINE_TILES && lattice_n >= FINE_LATTICE { FINE_LEAF_COST } else { LEAF_COST }
}

/// A ref's share of a sixteen-ref box test, in triangle tests.
pub const BOX_TEST_COST: f64 = 0.03;

/// How far, in box cells, a typical ray's box over a leaf (grown by the margin) reaches past a
/// ref's box when the two meet: each side of the ref's box is grown by this much to estimate the
/// chance that a ray through the tile passes it.
pub const RAY_CELLS: f64 = 32.0;

/// A ref's z range in quantized levels, closed: `lo ≤ hi`.
pub type Range = (u32, u32);

/// A ref as the split heuristic sees it: its z range, and what a ray that reaches it expects to
/// pay for it, in triangle tests ([`ref_weight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    pub z: Range,
    pub weight: f64,
}

/// What a ref whose box in its tile is `cells` (`x_lo, x_hi, y_lo, y_hi`) costs a ray that
/// reaches its leaf, in triangle tests: [`BOX_TEST_COST`], plus the fraction of the tile its box
/// covers once each side is grown by [`RAY_CELLS`] (the chance that its triangle is tested).
pub fn ref_weight(cells: [u8; 4]) -> f64 {
    let side = |lo: u8, hi: u8| ((hi.saturating_sub(lo) as f64 + 1.0 + RAY_CELLS) / BOX_CELLS as f64).min(1.0);
    BOX_TEST_COST + side(cells[0], cells[1]) * side(cells[2], cells[3])
}

/// The boundaries of the leaves of a tile whose refs are `refs`, all within `[lo, hi]`
/// (`lo < hi`): `lo`, the split points in increasing order, `hi`. Leaf `k` is the closed slab
/// between boundaries `k` and `k + 1`; a ref belongs to every leaf it meets. Deterministic: the
/// same refs in any order give the same boundaries.
pub fn boundaries(refs: &[Slab], lo: u32, hi: u32, policy: &DepthPolicy, cost: f64, out: &mut Vec<u32>) {
    out.clear();
    out.push(lo);
    let mut scratch = Scratch { leaf_cost: cost, ..Scratch::default() };
    split(refs.to_vec(), lo, hi, 0, policy, out, &mut scratch);
}

#[derive(Default)]
struct Scratch {
    /// The cost of visiting a leaf, in triangle tests ([`leaf_cost`]).
    leaf_cost: f64,
    /// The refs' starts and ends with their weights, each in increasing order.
    starts: Vec<(u32, f64)>,
    ends: Vec<(u32, f64)>,
    candidates: Vec<u32>,
}

/// Splits `[a, b]` over `refs` (each meeting it) recursively, appending the far boundary of each
/// leaf in order.
fn split(refs: Vec<Slab>, a: u32, b: u32, depth: u32, policy: &DepthPolicy, out: &mut Vec<u32>, s: &mut Scratch) {
    match best_split(&refs, a, b, depth, policy, s) {
        None => out.push(b),
        Some(at) => {
            // A ref ending before `at` is left of it, one starting after it right of it; one
            // that meets `at` (the closed boundary both leaves share) is in both.
            let left: Vec<Slab> = refs.iter().copied().filter(|r| r.z.0 <= at).collect();
            let right: Vec<Slab> = refs.into_iter().filter(|r| r.z.1 >= at).collect();
            split(left, a, at, depth + 1, policy, out, s);
            split(right, at, b, depth + 1, policy, out, s);
        }
    }
}

/// The split point of `[a, b]` that costs least, if it costs less than one leaf.
fn best_split(refs: &[Slab], a: u32, b: u32, depth: u32, policy: &DepthPolicy, s: &mut Scratch) -> Option<u32> {
    let n = refs.len();
    if n <= policy.leaf_size as usize || depth >= policy.max_depth || b - a < 2 {
        return None;
    }
    // Sorted by position, then weight, so that every sum below runs in an order that does not
    // depend on the refs' order.
    let by_key = |x: &(u32, f64)| (x.0, x.1.to_bits());
    s.starts.clear();
    s.starts.extend(refs.iter().map(|r| (r.z.0, r.weight)));
    s.starts.sort_unstable_by_key(by_key);
    s.ends.clear();
    s.ends.extend(refs.iter().map(|r| (r.z.1, r.weight)));
    s.ends.sort_unstable_by_key(by_key);
    let total: f64 = s.starts.iter().map(|x| x.1).sum();
    // Candidates just past a ref's end (it then stays left only) and just before a ref's start
    // (it stays right only), strictly inside the range.
    s.candidates.clear();
    s.candidates.extend(s.ends.iter().map(|e| e.0 + 1).chain(s.starts.iter().map(|b| b.0.saturating_sub(1))));
    s.candidates.retain(|&c| c > a && c < b);
    s.candidates.sort_unstable();
    s.candidates.dedup();
    let length = (b - a) as f64;
    let (mut best_cost, mut best) = (total, None);
    let (mut started, mut ended) = (0, 0);
    let (mut left, mut gone) = (0.0, 0.0);
    for &at in &s.candidates {
        // Refs meeting [a, at]: those starting at or before `at`; meeting [at, b]: those not
        // ended before `at`.
        while started < n && s.starts[started].0 <= at {
            left += s.starts[started].1;
            started += 1;
        }
        while ended < n && s.ends[ended].0 < at {
            gone += s.ends[ended].1;
            ended += 1;
        }
        let right = total - gone;
        let cost = s.leaf_cost + ((at - a) as f64 * left + (b - at) as f64 * right) / length;
        if cost < best_cost {
            (best_cost, best) = (cost, Some(at));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy(leaf_size: u32, max_depth: u32) -> DepthPolicy {
        DepthPolicy { leaf_size, max_depth }
    }

    /// A ref whose box covers the whole tile.
    const WHOLE: [u8; 4] = [0, 255, 0, 255];

    fn leaves(refs: &[Range], lo: u32, hi: u32, p: DepthPolicy) -> Vec<u32> {
        leaves_boxed(refs, WHOLE, lo, hi, p)
    }

    fn leaves_boxed(refs: &[Range], cells: [u8; 4], lo: u32, hi: u32, p: DepthPolicy) -> Vec<u32> {
        let slabs: Vec<Slab> = refs.iter().map(|&z| Slab { z, weight: ref_weight(cells) }).collect();
        let mut out = Vec::new();
        boundaries(&slabs, lo, hi, &p, LEAF_COST, &mut out);
        out
    }

    /// Which leaves each ref lands in, and a check that every ref is in every leaf it meets.
    fn members(bounds: &[u32], refs: &[Range]) -> Vec<usize> {
        (0..bounds.len() - 1)
            .map(|k| refs.iter().filter(|r| r.0 <= bounds[k + 1] && r.1 >= bounds[k]).count())
            .collect()
    }

    #[test]
    fn two_separate_clusters_get_their_own_leaves_and_the_gap_between_them_none_of_their_refs() {
        let mut refs: Vec<Range> = (0..20).map(|i| (100 + i, 110 + i)).collect();
        refs.extend((0..20).map(|i| (5000 + i, 5010 + i)));
        let b = leaves(&refs, 100, 5029, policy(4, 8));
        assert_eq!((b[0], *b.last().unwrap()), (100, 5029));
        assert!(b.windows(2).all(|w| w[0] < w[1]), "{b:?}");
        let m = members(&b, &refs);
        assert!(m.contains(&0), "an empty leaf over the gap: {b:?} {m:?}");
        assert!(m.iter().all(|&c| c <= 20), "no leaf holds both clusters: {m:?}");
    }

    #[test]
    fn coincident_refs_stay_in_one_leaf() {
        let refs = vec![(1000, 1001); 5000];
        assert_eq!(leaves(&refs, 1000, 1001, policy(4, 12)), [1000, 1001]);
        let refs = vec![(1000, 3000); 5000];
        assert_eq!(leaves(&refs, 1000, 3000, policy(4, 12)), [1000, 3000]);
    }

    #[test]
    fn the_policy_bounds_the_leaves() {
        let refs: Vec<Range> = (0..1000).map(|i| (i * 60, i * 60 + 10)).collect();
        let few = leaves(&refs, 0, 60_000, policy(1000, 8));
        assert_eq!(few, [0, 60_000], "no split at or below leaf_size");
        let shallow = leaves(&refs, 0, 60_000, policy(1, 2));
        assert!(shallow.len() - 1 <= 4, "depth 2 makes at most 4 leaves: {shallow:?}");
        let deep = leaves(&refs, 0, 60_000, policy(1, 12));
        assert!(deep.len() - 1 > 64, "uniform refs are split finely: {} leaves", deep.len() - 1);
        assert!(members(&deep, &refs).iter().all(|&c| c <= 4), "{:?}", members(&deep, &refs));
    }

    #[test]
    fn the_order_of_the_refs_does_not_matter() {
        // Weights of every size, so that the sums would differ in their last bits if they ran in
        // the refs' order.
        let mut refs: Vec<Slab> = (0..300u32)
            .map(|i| {
                let z = ((i * 7919) % 9000, (i * 7919) % 9000 + i % 50);
                let (x, y) = ((i * 37 % 256) as u8, (i * 91 % 256) as u8);
                Slab { z, weight: ref_weight([x / 2, x, y / 3, y]) }
            })
            .collect();
        let mut a = Vec::new();
        boundaries(&refs, 0, 9100, &policy(4, 10), LEAF_COST, &mut a);
        assert!(a.len() > 2, "the refs are split: {a:?}");
        for round in 0..4 {
            refs.reverse();
            refs.rotate_left(round * 37);
            let mut b = Vec::new();
            boundaries(&refs, 0, 9100, &policy(4, 10), LEAF_COST, &mut b);
            assert_eq!(b, a);
        }
    }

    #[test]
    fn a_ref_weighs_its_box_test_and_the_chance_its_triangle_is_tested() {
        assert_eq!(ref_weight(WHOLE), BOX_TEST_COST + 1.0);
        let corner = ref_weight([0, 0, 0, 0]);
        let side = (1.0 + RAY_CELLS) / 256.0;
        assert!((corner - (BOX_TEST_COST + side * side)).abs() < 1e-12, "{corner}");
        // Growing a box never makes its ref cheaper; a box over half the tile is tested by about
        // half the rays on each axis.
        assert!(ref_weight([0, 10, 0, 10]) < ref_weight([0, 20, 0, 10]));
        assert!(ref_weight([0, 127, 0, 255]) < 0.7);
        // A lying box (lo above hi) weighs as a one-cell box.
        assert_eq!(ref_weight([9, 3, 0, 0]), corner);
    }

    #[test]
    fn refs_of_small_boxes_get_longer_leaves_than_refs_that_cover_the_tile() {
        // The same uniform z ranges: triangles that cover the whole tile are tested by every ray
        // that reaches them, so they are cut finely; triangles in a corner of the tile are
        // mostly rejected by the box test, so their leaves hold more of them.
        let refs: Vec<Range> = (0..2000).map(|i| (i * 30, i * 30 + 40)).collect();
        let whole = leaves_boxed(&refs, WHOLE, 0, 60_100, policy(1, 12));
        let corner = leaves_boxed(&refs, [0, 8, 0, 8], 0, 60_100, policy(1, 12));
        assert!(
            corner.len() * 3 < whole.len(),
            "{} leaves for small boxes, {} for whole-tile boxes",
            corner.len() - 1,
            whole.len() - 1
        );
        let most = |b: &[u32]| members(b, &refs).into_iter().max().unwrap();
        assert!(most(&corner) > 2 * most(&whole), "{} vs {}", most(&corner), most(&whole));
    }

    #[test]
    fn fine_grids_of_many_directions_pay_more_for_a_leaf_and_get_fewer_of_them() {
        assert_eq!(leaf_cost(FINE_TILES - 1, 64), LEAF_COST);
        assert_eq!(leaf_cost(FINE_TILES, FINE_LATTICE - 1), LEAF_COST);
        assert_eq!(leaf_cost(FINE_TILES, FINE_LATTICE), FINE_LEAF_COST);
        assert_eq!(leaf_cost(65536, 4096), FINE_LEAF_COST);
        // Small boxes spread along z, as on a dense tile of a scanned surface: a dearer leaf
        // splits them into fewer, longer leaves, and every ref is still in every leaf it meets.
        let slabs: Vec<Slab> = (0..400u32)
            .map(|i| Slab {
                z: (i * 25, i * 25 + 30),
                weight: ref_weight([(i % 200) as u8, (i % 200) as u8 + 20, 0, 20]),
            })
            .collect();
        let (mut cheap, mut dear) = (Vec::new(), Vec::new());
        boundaries(&slabs, 0, 10_030, &policy(1, 12), leaf_cost(64, 6), &mut cheap);
        boundaries(&slabs, 0, 10_030, &policy(1, 12), leaf_cost(128, 6), &mut dear);
        assert!(dear.len() < cheap.len(), "{} leaves at 128² tiles, {} at 64²", dear.len() - 1, cheap.len() - 1);
        assert!(dear.len() > 2, "still split: {dear:?}");
        let refs: Vec<Range> = slabs.iter().map(|s| s.z).collect();
        let held: usize = members(&dear, &refs).iter().sum();
        assert!(held >= refs.len(), "{held} memberships for {} refs", refs.len());
    }
}
