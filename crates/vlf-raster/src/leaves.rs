//! Where a tile's leaves go (paper §7: "a better split heuristic than the mid-point"): the tile's
//! z range is cut into consecutive slabs by a one-dimensional surface-area heuristic over the z
//! ranges of the triangles in it (`formats/vlf.md` §6.3).
//!
//! A ray walks a tile's leaves in order along the beam and stops once it has a hit within the part
//! already searched, so a leaf's expected cost is roughly the chance that a ray reaches it (its
//! share of the tile's length) times its refs. A split at `s` of a range `[a, b]` holding `N` refs
//! costs `C + ((s − a)·N_a + (b − s)·N_b) / (b − a)` ref tests, against `N` for a single leaf,
//! where `N_a` and `N_b` count the refs that meet each side (a ref straddling `s` is in both) and
//! `C` ([`LEAF_COST`]) is what visiting one more leaf costs in ref tests. The best split is taken
//! while it is cheaper, so dense parts get small leaves, empty gaps become empty leaves of no
//! refs, and refs that all overlap (coincident triangles) stay in one leaf instead of being copied
//! into many. The old mid-point BSP copied a pile of coincident triangles into every one of its
//! `2^D` leaves.

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

/// The cost of visiting a leaf, in ref tests (tuned by `vlf-bench peers --sweep`): a leaf visit
/// computes the ray's box and starts a group of sixteen box tests, and ends a ray's search only
/// at its far side.
pub const LEAF_COST: f64 = 3.0;

/// A ref's z range in quantized levels, closed: `lo ≤ hi`.
pub type Range = (u32, u32);

/// The boundaries of the leaves of a tile whose refs have the z ranges `refs`, all within
/// `[lo, hi]` (`lo < hi`): `lo`, the split points in increasing order, `hi`. Leaf `k` is the
/// closed slab between boundaries `k` and `k + 1`; a ref belongs to every leaf it meets.
/// Deterministic: the same ranges in any order give the same boundaries.
pub fn boundaries(refs: &[Range], lo: u32, hi: u32, policy: &DepthPolicy, out: &mut Vec<u32>) {
    out.clear();
    out.push(lo);
    let mut scratch = Scratch::default();
    split(refs.to_vec(), lo, hi, 0, policy, out, &mut scratch);
}

#[derive(Default)]
struct Scratch {
    starts: Vec<u32>,
    ends: Vec<u32>,
    candidates: Vec<u32>,
}

/// Splits `[a, b]` over `refs` (each meeting it) recursively, appending the far boundary of each
/// leaf in order.
fn split(refs: Vec<Range>, a: u32, b: u32, depth: u32, policy: &DepthPolicy, out: &mut Vec<u32>, s: &mut Scratch) {
    match best_split(&refs, a, b, depth, policy, s) {
        None => out.push(b),
        Some(at) => {
            // A ref ending before `at` is left of it, one starting after it right of it; one
            // that meets `at` (the closed boundary both leaves share) is in both.
            let left: Vec<Range> = refs.iter().copied().filter(|r| r.0 <= at).collect();
            let right: Vec<Range> = refs.into_iter().filter(|r| r.1 >= at).collect();
            split(left, a, at, depth + 1, policy, out, s);
            split(right, at, b, depth + 1, policy, out, s);
        }
    }
}

/// The split point of `[a, b]` that costs least, if it costs less than one leaf.
fn best_split(refs: &[Range], a: u32, b: u32, depth: u32, policy: &DepthPolicy, s: &mut Scratch) -> Option<u32> {
    let n = refs.len();
    if n <= policy.leaf_size as usize || depth >= policy.max_depth || b - a < 2 {
        return None;
    }
    s.starts.clear();
    s.starts.extend(refs.iter().map(|r| r.0));
    s.starts.sort_unstable();
    s.ends.clear();
    s.ends.extend(refs.iter().map(|r| r.1));
    s.ends.sort_unstable();
    // Candidates just past a ref's end (it then stays left only) and just before a ref's start
    // (it stays right only), strictly inside the range.
    s.candidates.clear();
    s.candidates.extend(s.ends.iter().map(|&e| e + 1).chain(s.starts.iter().map(|&b| b.saturating_sub(1))));
    s.candidates.retain(|&c| c > a && c < b);
    s.candidates.sort_unstable();
    s.candidates.dedup();
    let length = (b - a) as f64;
    let (mut best_cost, mut best) = (n as f64, None);
    let (mut left, mut ended) = (0, 0);
    for &at in &s.candidates {
        // Refs meeting [a, at]: those starting at or before `at`; meeting [at, b]: those not
        // ended before `at`.
        while left < n && s.starts[left] <= at {
            left += 1;
        }
        while ended < n && s.ends[ended] < at {
            ended += 1;
        }
        let right = n - ended;
        let cost = LEAF_COST + ((at - a) as f64 * left as f64 + (b - at) as f64 * right as f64) / length;
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

    fn leaves(refs: &[Range], lo: u32, hi: u32, p: DepthPolicy) -> Vec<u32> {
        let mut out = Vec::new();
        boundaries(refs, lo, hi, &p, &mut out);
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
        let mut refs: Vec<Range> = (0..300u32).map(|i| ((i * 7919) % 9000, (i * 7919) % 9000 + i % 50)).collect();
        let a = leaves(&refs, 0, 9100, policy(4, 10));
        refs.reverse();
        assert_eq!(leaves(&refs, 0, 9100, policy(4, 10)), a);
    }
}
