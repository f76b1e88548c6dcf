//! The top level: a bounding-volume hierarchy over the instances' world boxes, one instance per
//! leaf. Its cost depends on the number of instances, never on their triangles.
//!
//! - **Build** (`Scene::rebuild`, after instances were added in bulk, and whenever the tree has
//!   degraded): binned surface-area heuristic, top down, `O(n log n)` for `n` instances; below a
//!   depth of [`SAH_DEPTH`] the split is the median, so the tree is never deeper than about
//!   `SAH_DEPTH + log₂ n`.
//! - **Update** (a transform changed): the leaf's box is replaced and its ancestors refitted if it
//!   stays inside its parent's box, else the leaf is removed and inserted again, `O(depth)`.
//!   **Insert** puts a leaf beside the node whose box grows least (a greedy descent, `O(depth)`);
//!   **remove** splices its parent out, `O(depth)`.
//! - Refits and inserts can make the boxes loose (instances that moved far apart keep a common
//!   parent). The sum of the inner boxes' surface areas is kept up to date; when it exceeds
//!   [`REBUILD_FACTOR`] times its value after the last build, the tree is rebuilt. Rebuilds are
//!   therefore amortised over many updates.
//! - Every node knows its leaf count and height, so the tree's depth is exact. An insert that
//!   takes it past [`MAX_DEPTH`] (the traversal's stack) rebuilds only the subtree of its leaf's
//!   highest unbalanced ancestor, a scapegoat tree's rule: inserts in an order that follows space
//!   grow a spine there, and rebuilding the whole tree for each spine cost `O(n log n)` every
//!   seventy-odd inserts.
//!
//! Boxes are f64. Traversal visits children nearest first and skips a subtree whose box starts
//! beyond the best hit so far.

// `!(a <= b)` is meant: it is true when either side is NaN, which must fail the test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

/// A box: `lo ≤ hi` on every axis, or empty (`lo = +∞`, `hi = −∞`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl Aabb {
    /// The empty box.
    pub const EMPTY: Aabb = Aabb { lo: [f64::INFINITY; 3], hi: [f64::NEG_INFINITY; 3] };

    pub fn is_empty(&self) -> bool {
        !(0..3).all(|k| self.lo[k] <= self.hi[k])
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            lo: std::array::from_fn(|k| self.lo[k].min(o.lo[k])),
            hi: std::array::from_fn(|k| self.hi[k].max(o.hi[k])),
        }
    }

    /// Half the surface area (the heuristic's measure); 0 for an empty box.
    pub fn half_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let e: [f64; 3] = std::array::from_fn(|k| self.hi[k] - self.lo[k]);
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// Whether `o` lies inside this box (an empty `o` always does).
    pub fn contains(&self, o: &Aabb) -> bool {
        o.is_empty() || (0..3).all(|k| self.lo[k] <= o.lo[k] && o.hi[k] <= self.hi[k])
    }

    fn centroid(&self, k: usize) -> f64 {
        0.5 * (self.lo[k] + self.hi[k])
    }
}

/// The part of a ray the traversal needs: its origin, the inverses of its direction's components
/// (infinite for a zero component) and its interval.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    pub org: [f64; 3],
    pub dir: [f64; 3],
    pub inv: [f64; 3],
    pub tmin: f64,
}

impl BoxRay {
    pub fn new(org: [f64; 3], dir: [f64; 3], tmin: f64) -> BoxRay {
        BoxRay { org, dir, inv: dir.map(|d| 1.0 / d), tmin }
    }

    /// Where the ray enters `b` on `[tmin, tmax]`, or `None` if it misses the box there. A box
    /// face the ray runs along counts as inside (closed boxes).
    #[inline]
    pub fn enter(&self, b: &Aabb, tmax: f64) -> Option<f64> {
        let (mut t0, mut t1) = (self.tmin, tmax);
        for k in 0..3 {
            if self.dir[k] == 0.0 {
                if !(self.org[k] >= b.lo[k] && self.org[k] <= b.hi[k]) {
                    return None;
                }
                continue;
            }
            let ta = (b.lo[k] - self.org[k]) * self.inv[k];
            let tb = (b.hi[k] - self.org[k]) * self.inv[k];
            let (near, far) = if ta <= tb { (ta, tb) } else { (tb, ta) };
            if near > t0 {
                t0 = near;
            }
            if far < t1 {
                t1 = far;
            }
        }
        (t0 <= t1).then_some(t0)
    }
}

/// Below this depth the build splits by the surface-area heuristic, deeper by the median.
pub const SAH_DEPTH: usize = 40;
/// The tree is never deeper than this (an insert that would make it deeper rebuilds a subtree).
pub const MAX_DEPTH: usize = 96;
/// The tree is rebuilt when its inner boxes' summed area grows past this factor of the last build's.
pub const REBUILD_FACTOR: f64 = 2.0;
/// A node is unbalanced when one child holds more than this share of its leaves (see
/// `Bvh::rebuild_scapegoat`).
pub const UNBALANCED: f64 = 0.7;
/// Bins of the surface-area heuristic.
const BINS: usize = 16;
const NONE: u32 = u32::MAX;

use vlf_geom::Counter;

#[derive(Clone, Copy, Debug)]
struct Node {
    b: Aabb,
    parent: u32,
    /// Inner node: the children. Leaf: `left` is the instance and `right` is [`NONE`].
    left: u32,
    right: u32,
}

// One cache line a node on the traversal's path.
const _: () = assert!(size_of::<Node>() == 64);

/// A node's leaf count (1 for a leaf) and the height of its subtree (0 for a leaf), kept beside
/// the nodes rather than in them: inserts and rebuilds read them, traversal does not, and a
/// [`Node`] stays 64 bytes (72 with these in it traced primary rays 15–20% slower).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Shape {
    count: u32,
    height: u32,
}

impl Shape {
    const LEAF: Shape = Shape { count: 1, height: 0 };

    fn above(l: Shape, r: Shape) -> Shape {
        Shape { count: l.count + r.count, height: 1 + l.height.max(r.height) }
    }
}

impl Node {
    fn leaf(b: Aabb, parent: u32, key: u32) -> Node {
        Node { b, parent, left: key, right: NONE }
    }

    fn is_leaf(&self) -> bool {
        self.right == NONE
    }
}

/// The hierarchy. Instances are named by `u32` keys chosen by the caller.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Each node's leaf count and height, by node id.
    shape: Vec<Shape>,
    root: u32,
    /// Node slots free for reuse.
    free: Vec<u32>,
    /// The leaf node of each key, or [`NONE`].
    leaf_of: Vec<u32>,
    leaves: usize,
    /// The sum of the inner boxes' half areas now, and after the last build.
    area: f64,
    built_area: f64,
    /// Full builds so far.
    pub builds: u64,
}

impl Bvh {
    pub fn new() -> Bvh {
        Bvh { root: NONE, ..Bvh::default() }
    }

    /// The box around every leaf.
    pub fn bounds(&self) -> Aabb {
        if self.root == NONE { Aabb::EMPTY } else { self.nodes[self.root as usize].b }
    }

    /// Rebuilds the tree over `items` (key, box), replacing everything it held. `O(n log n)`.
    pub fn build(&mut self, items: &[(u32, Aabb)]) {
        self.nodes.clear();
        self.shape.clear();
        self.free.clear();
        self.leaf_of.iter_mut().for_each(|l| *l = NONE);
        self.root = NONE;
        self.leaves = items.len();
        self.builds += 1;
        if let Some(max) = items.iter().map(|i| i.0).max()
            && self.leaf_of.len() <= max as usize
        {
            self.leaf_of.resize(max as usize + 1, NONE);
        }
        if !items.is_empty() {
            let mut work: Vec<(u32, Aabb)> = items.to_vec();
            self.nodes.reserve(2 * items.len());
            self.shape.reserve(2 * items.len());
            self.root = self.build_range(&mut work, NONE, 0);
        }
        self.area = self.nodes.iter().filter(|n| !n.is_leaf()).map(|n| n.b.half_area()).sum();
        self.built_area = self.area;
    }

    /// Builds a subtree over `items` under `parent`, its nodes from the free slots first;
    /// surface-area splits above [`SAH_DEPTH`] (counting from `depth`), medians below.
    fn build_range(&mut self, items: &mut [(u32, Aabb)], parent: u32, depth: usize) -> u32 {
        if items.len() == 1 {
            let (key, b) = items[0];
            let me = self.alloc(Node::leaf(b, parent, key), Shape::LEAF);
            self.leaf_of[key as usize] = me;
            return me;
        }
        let b = items.iter().fold(Aabb::EMPTY, |acc, i| acc.union(&i.1));
        let me = self.alloc(Node { b, parent, left: NONE, right: NONE }, Shape::default());
        let mid = split(items, depth < SAH_DEPTH);
        let (l, r) = items.split_at_mut(mid);
        let left = self.build_range(l, me, depth + 1);
        let right = self.build_range(r, me, depth + 1);
        self.shape[me as usize] = Shape::above(self.shape[left as usize], self.shape[right as usize]);
        let node = &mut self.nodes[me as usize];
        (node.left, node.right) = (left, right);
        me
    }

    /// The height of the tree: the most inner nodes on a path from the root to a leaf.
    pub fn depth(&self) -> usize {
        if self.root == NONE { 0 } else { self.shape[self.root as usize].height as usize }
    }

    /// The leaves' current keys and boxes.
    pub fn items(&self) -> Vec<(u32, Aabb)> {
        self.leaf_of
            .iter()
            .enumerate()
            .filter(|&(_, &n)| n != NONE)
            .map(|(k, &n)| (k as u32, self.nodes[n as usize].b))
            .collect()
    }

    /// Rebuilds if the boxes have grown loose (see the module's documentation). The depth needs
    /// no check here: an insert keeps it within [`MAX_DEPTH`] itself.
    pub fn maybe_rebuild(&mut self) {
        debug_assert!(self.depth() <= MAX_DEPTH, "depth {}", self.depth());
        if self.area > REBUILD_FACTOR * self.built_area.max(f64::MIN_POSITIVE) {
            let items = self.items();
            self.build(&items);
        }
    }

    fn alloc(&mut self, n: Node, shape: Shape) -> u32 {
        match self.free.pop() {
            Some(i) => {
                self.nodes[i as usize] = n;
                self.shape[i as usize] = shape;
                i
            }
            None => {
                self.nodes.push(n);
                self.shape.push(shape);
                (self.nodes.len() - 1) as u32
            }
        }
    }

    /// Adds leaf `key` with box `b` beside the subtree whose box grows least. `O(depth)`.
    pub fn insert(&mut self, key: u32, b: Aabb) {
        if self.leaf_of.len() <= key as usize {
            self.leaf_of.resize(key as usize + 1, NONE);
        }
        debug_assert_eq!(self.leaf_of[key as usize], NONE, "key {key} is in the tree");
        self.leaves += 1;
        let leaf = self.alloc(Node::leaf(b, NONE, key), Shape::LEAF);
        self.leaf_of[key as usize] = leaf;
        if self.root == NONE {
            self.root = leaf;
            return;
        }
        let mut at = self.root;
        while !self.nodes[at as usize].is_leaf() {
            let n = self.nodes[at as usize];
            let grow = |c: u32| {
                let cb = self.nodes[c as usize].b;
                cb.union(&b).half_area() - cb.half_area()
            };
            at = if grow(n.left) <= grow(n.right) { n.left } else { n.right };
        }
        let sibling = at;
        let parent = self.nodes[sibling as usize].parent;
        let leaves = Shape::above(Shape::LEAF, Shape::LEAF);
        let inner = self.alloc(Node { b: Aabb::EMPTY, parent, left: sibling, right: leaf }, leaves);
        self.nodes[sibling as usize].parent = inner;
        self.nodes[leaf as usize].parent = inner;
        if parent == NONE {
            self.root = inner;
        } else {
            let p = &mut self.nodes[parent as usize];
            if p.left == sibling { p.left = inner } else { p.right = inner }
        }
        self.refit(inner);
        if self.depth() > MAX_DEPTH {
            self.rebuild_scapegoat(leaf);
        }
    }

    /// Brings the tree back under [`MAX_DEPTH`] after the insert of `leaf` took it past, by
    /// rebuilding only the subtree of its highest ancestor whose children's leaf counts differ by
    /// more than [`UNBALANCED`] (a scapegoat tree's rule): in an order of inserts that follows
    /// space, each new leaf goes beside the last and a spine grows, and rebuilding the whole
    /// tree every time it got too deep cost `O(n log n)` every seventy-odd inserts. The subtree
    /// is rebuilt with median splits, which balance it; the whole tree only if the scapegoat is
    /// the root, or if the subtree rebuilt still leaves the tree too deep.
    fn rebuild_scapegoat(&mut self, leaf: u32) {
        let mut scapegoat = NONE;
        let mut at = self.nodes[leaf as usize].parent;
        while at != NONE {
            let n = self.nodes[at as usize];
            let heavier = self.shape[n.left as usize].count.max(self.shape[n.right as usize].count);
            if heavier as f64 > UNBALANCED * self.shape[at as usize].count as f64 {
                scapegoat = at;
            }
            at = n.parent;
        }
        if scapegoat != NONE && scapegoat != self.root {
            self.rebuild_subtree(scapegoat);
        }
        if self.depth() > MAX_DEPTH {
            let items = self.items();
            self.build(&items);
        }
    }

    /// Rebuilds the subtree at `top` over the same leaves, with median splits; `O(s log s)` for
    /// its `s` leaves. Its box, and so every box above it, stays as it was.
    fn rebuild_subtree(&mut self, top: u32) {
        let parent = self.nodes[top as usize].parent;
        let mut items = Vec::with_capacity(self.shape[top as usize].count as usize);
        let mut pending = vec![top];
        while let Some(at) = pending.pop() {
            let n = self.nodes[at as usize];
            self.free.push(at);
            if n.is_leaf() {
                items.push((n.left, n.b));
            } else {
                self.area -= n.b.half_area();
                pending.extend([n.left, n.right]);
            }
        }
        let new = self.build_range(&mut items, parent, SAH_DEPTH);
        let mut pending = vec![new];
        while let Some(at) = pending.pop() {
            let n = self.nodes[at as usize];
            if !n.is_leaf() {
                self.area += n.b.half_area();
                pending.extend([n.left, n.right]);
            }
        }
        let p = &mut self.nodes[parent as usize];
        if p.left == top {
            p.left = new
        } else {
            p.right = new
        }
        self.refit(parent);
    }

    /// Removes leaf `key`. `O(depth)`. Does nothing for a key not in the tree.
    pub fn remove(&mut self, key: u32) {
        let Some(&leaf) = self.leaf_of.get(key as usize).filter(|&&l| l != NONE) else { return };
        self.leaf_of[key as usize] = NONE;
        self.leaves -= 1;
        self.free.push(leaf);
        let parent = self.nodes[leaf as usize].parent;
        if parent == NONE {
            self.root = NONE;
            return;
        }
        let p = self.nodes[parent as usize];
        let sibling = if p.left == leaf { p.right } else { p.left };
        let grand = p.parent;
        self.area -= p.b.half_area();
        self.free.push(parent);
        self.nodes[sibling as usize].parent = grand;
        if grand == NONE {
            self.root = sibling;
        } else {
            let g = &mut self.nodes[grand as usize];
            if g.left == parent {
                g.left = sibling
            } else {
                g.right = sibling
            }
            self.refit(grand);
        }
    }

    /// Gives leaf `key` the box `b`. `O(depth)`: if `b` stays inside the leaf's parent's box,
    /// the ancestors are refitted in place; otherwise the leaf is removed and inserted again
    /// beside the subtree its new box grows least, so that an instance that moved far does not
    /// stretch the boxes of its old neighbours (which refitting alone would, slowing every ray
    /// that crosses them until the next rebuild).
    pub fn update(&mut self, key: u32, b: Aabb) {
        let Some(&leaf) = self.leaf_of.get(key as usize).filter(|&&l| l != NONE) else { return };
        let parent = self.nodes[leaf as usize].parent;
        if parent == NONE || self.nodes[parent as usize].b.contains(&b) {
            self.nodes[leaf as usize].b = b;
            if parent != NONE {
                self.refit(parent);
            }
            return;
        }
        self.remove(key);
        self.insert(key, b);
    }

    /// Recomputes the boxes, leaf counts and heights of `from` and its ancestors, keeping the
    /// area sum current.
    fn refit(&mut self, from: u32) {
        let mut at = from;
        while at != NONE {
            let n = self.nodes[at as usize];
            let b = self.nodes[n.left as usize].b.union(&self.nodes[n.right as usize].b);
            self.area += b.half_area() - n.b.half_area();
            self.nodes[at as usize].b = b;
            self.shape[at as usize] = Shape::above(self.shape[n.left as usize], self.shape[n.right as usize]);
            at = n.parent;
        }
    }

    /// Visits the leaves whose boxes the ray enters before `tmax()`, nearest box first, calling
    /// `visit(key, counter)`; `tmax` is read again after every visit, so a closest-hit search
    /// narrows as it finds hits. Stops when `visit` returns `true`. Counts every node visited as a
    /// cell.
    #[inline]
    pub fn traverse<C: Counter>(
        &self,
        ray: &BoxRay,
        tmax: impl Fn() -> f64,
        counter: &mut C,
        mut visit: impl FnMut(u32, &mut C) -> bool,
    ) {
        if self.root == NONE {
            return;
        }
        // The depth is at most MAX_DEPTH + 1 between rebuilds, and each level pushes one node.
        // Node ids only: a zeroed `[u32; _]` costs a few vector stores per ray, where pairs with
        // their entry `t` cost a loop of scalar stores that took half the traversal's time on a
        // one-instance scene. The entry is computed again when a node is popped (against the
        // best hit found since, which can only skip more).
        let mut stack = [0u32; MAX_DEPTH + 4];
        if ray.enter(&self.nodes[self.root as usize].b, tmax()).is_none() {
            return;
        }
        stack[0] = self.root;
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let at = stack[top];
            let limit = tmax();
            let n = &self.nodes[at as usize];
            if at != self.root && ray.enter(&n.b, limit).is_none() {
                continue;
            }
            counter.cell();
            if n.is_leaf() {
                if visit(n.left, counter) {
                    return;
                }
                continue;
            }
            let a = ray.enter(&self.nodes[n.left as usize].b, limit).map(|t| (n.left, t));
            let b = ray.enter(&self.nodes[n.right as usize].b, limit).map(|t| (n.right, t));
            let (near, far) = match (a, b) {
                (Some(a), Some(b)) if b.1 < a.1 => (Some(b), Some(a)),
                (a, b) => (a.or(b), a.and(b)),
            };
            // Far first, so that the near child is popped next.
            for (c, _) in [far, near].into_iter().flatten() {
                if top < stack.len() {
                    stack[top] = c;
                    top += 1;
                }
            }
        }
    }
}

/// Partitions `items` (at least two) and returns the size of the left part (1 to len − 1): the
/// binned surface-area split if `sah`, else the median along the longest axis of the centroids.
fn split(items: &mut [(u32, Aabb)], sah: bool) -> usize {
    let n = items.len();
    let cb = items.iter().fold(Aabb::EMPTY, |acc, i| {
        let c: [f64; 3] = std::array::from_fn(|k| i.1.centroid(k));
        acc.union(&Aabb { lo: c, hi: c })
    });
    let extent: [f64; 3] = std::array::from_fn(|k| cb.hi[k] - cb.lo[k]);
    let axis = (0..3).fold(0, |best, k| if extent[k] > extent[best] { k } else { best });
    if sah && extent[axis] > 0.0 {
        let scale = BINS as f64 / extent[axis];
        let bin = |i: &(u32, Aabb)| (((i.1.centroid(axis) - cb.lo[axis]) * scale) as usize).min(BINS - 1);
        let mut boxes = [Aabb::EMPTY; BINS];
        let mut counts = [0usize; BINS];
        for i in items.iter() {
            let k = bin(i);
            boxes[k] = boxes[k].union(&i.1);
            counts[k] += 1;
        }
        // Cost of splitting after bin k: area(left)·count(left) + area(right)·count(right).
        let mut right_area = [0.0; BINS];
        let mut acc = Aabb::EMPTY;
        for k in (1..BINS).rev() {
            acc = acc.union(&boxes[k]);
            right_area[k] = acc.half_area();
        }
        let (mut best, mut best_cost) = (None, f64::INFINITY);
        let (mut left, mut left_n) = (Aabb::EMPTY, 0);
        for k in 0..BINS - 1 {
            left = left.union(&boxes[k]);
            left_n += counts[k];
            if left_n == 0 || left_n == n {
                continue;
            }
            let cost = left.half_area() * left_n as f64 + right_area[k + 1] * (n - left_n) as f64;
            if cost < best_cost {
                (best, best_cost) = (Some(k), cost);
            }
        }
        if let Some(k) = best {
            // A partition by bin; at least one item on each side.
            let mut i = 0;
            for j in 0..n {
                if bin(&items[j]) <= k {
                    items.swap(i, j);
                    i += 1;
                }
            }
            if i > 0 && i < n {
                return i;
            }
        }
    }
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| a.1.centroid(axis).total_cmp(&b.1.centroid(axis)));
    mid
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(c: [f64; 3], r: f64) -> Aabb {
        Aabb { lo: c.map(|v| v - r), hi: c.map(|v| v + r) }
    }

    /// The tree's bookkeeping recomputed from its leaves up: every inner node's box, leaf count,
    /// height and parent link; the area sum; the leaf of each key. Returns the root's height.
    fn structure(bvh: &Bvh) -> usize {
        fn walk(bvh: &Bvh, at: u32, parent: u32, area: &mut f64, leaves: &mut usize) -> (Aabb, u32, u32) {
            let n = bvh.nodes[at as usize];
            assert_eq!(n.parent, parent, "node {at}: parent link");
            if n.is_leaf() {
                assert_eq!(bvh.leaf_of[n.left as usize], at, "key {}: leaf", n.left);
                *leaves += 1;
                assert_eq!(bvh.shape[at as usize], Shape::LEAF, "leaf {at}");
                return (n.b, 1, 0);
            }
            let (lb, lc, lh) = walk(bvh, n.left, at, area, leaves);
            let (rb, rc, rh) = walk(bvh, n.right, at, area, leaves);
            let b = lb.union(&rb);
            let shape = bvh.shape[at as usize];
            assert_eq!((n.b, shape.count, shape.height), (b, lc + rc, 1 + lh.max(rh)), "node {at}");
            *area += b.half_area();
            (b, lc + rc, 1 + lh.max(rh))
        }
        if bvh.root == NONE {
            return 0;
        }
        let (mut area, mut leaves) = (0.0, 0);
        let (_, _, height) = walk(bvh, bvh.root, NONE, &mut area, &mut leaves);
        assert_eq!(leaves, bvh.leaves);
        assert!((area - bvh.area).abs() <= 1e-9 * area.max(1.0), "area {area} against {}", bvh.area);
        assert_eq!(height as usize, bvh.depth());
        height as usize
    }

    /// Every leaf a ray's line enters, by brute force, against the traversal's.
    fn check(bvh: &Bvh, boxes: &[(u32, Aabb)]) {
        structure(bvh);
        let mut s = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..300 {
            let ray = BoxRay::new([rnd() * 30.0, rnd() * 30.0, rnd() * 30.0], [rnd(), rnd(), rnd()], 0.0);
            let mut want: Vec<u32> =
                boxes.iter().filter(|(_, b)| ray.enter(b, f64::INFINITY).is_some()).map(|i| i.0).collect();
            let mut got = Vec::new();
            bvh.traverse(
                &ray,
                || f64::INFINITY,
                &mut (),
                |k, _| {
                    got.push(k);
                    false
                },
            );
            want.sort();
            got.sort();
            assert_eq!(got, want);
        }
    }

    #[test]
    fn builds_inserts_moves_and_removes_keep_every_leaf_reachable() {
        let mut boxes: Vec<(u32, Aabb)> = (0..200u32)
            .map(|i| (i, cube([(i % 10) as f64 * 3.0 - 15.0, (i / 10) as f64 - 10.0, (i % 7) as f64], 0.4)))
            .collect();
        let mut bvh = Bvh::new();
        bvh.build(&boxes[..100]);
        check(&bvh, &boxes[..100]);
        for &(k, b) in &boxes[100..] {
            bvh.insert(k, b);
        }
        check(&bvh, &boxes);
        for i in (0..200).step_by(3) {
            boxes[i].1 = cube([i as f64 * 0.1 - 10.0, 5.0, -(i as f64) * 0.05], 0.3 + i as f64 * 0.01);
            bvh.update(boxes[i].0, boxes[i].1);
        }
        check(&bvh, &boxes);
        for i in (0..200).rev().step_by(4) {
            bvh.remove(boxes[i].0);
            boxes.remove(i);
        }
        assert_eq!((bvh.leaves, bvh.items().len()), (boxes.len(), boxes.len()));
        check(&bvh, &boxes);
        bvh.maybe_rebuild();
        let items = bvh.items();
        bvh.build(&items);
        check(&bvh, &boxes);
    }

    /// Leaves inserted one at a time in an order that follows space (rows of a grid) each go
    /// beside the last and grow a spine. The spine's subtree is rebuilt, not the whole tree: the
    /// tree stays within MAX_DEPTH after every insert, and is built in full at most a few times.
    #[test]
    fn a_row_of_inserts_rebuilds_its_spine_not_the_tree() {
        let boxes: Vec<(u32, Aabb)> =
            (0..20_000u32).map(|i| (i, cube([(i % 200) as f64, (i / 200) as f64, 0.0], 0.3))).collect();
        let mut bvh = Bvh::new();
        for (n, &(k, b)) in boxes.iter().enumerate() {
            bvh.insert(k, b);
            bvh.maybe_rebuild();
            assert!(bvh.depth() <= MAX_DEPTH, "after {} inserts: depth {}", n + 1, bvh.depth());
            if n % 2_500 == 0 {
                structure(&bvh);
            }
        }
        check(&bvh, &boxes);
        // Before, the whole tree was also rebuilt every seventy-odd inserts for its depth (about
        // 260 builds here, each of all the leaves so far). Now only the area rule rebuilds it in
        // full, each time the leaves have grown by a fifth or so: 41 builds, whose sizes sum to
        // a few times the final count.
        assert!(bvh.builds <= 50, "{} full builds", bvh.builds);
        // Removing every other leaf and inserting them again, in order, keeps it so.
        for &(k, _) in boxes.iter().step_by(2) {
            bvh.remove(k);
        }
        for &(k, b) in boxes.iter().step_by(2) {
            bvh.insert(k, b);
        }
        check(&bvh, &boxes);
        assert!(bvh.depth() <= MAX_DEPTH);
    }

    #[test]
    fn identical_boxes_give_a_shallow_tree() {
        let boxes: Vec<(u32, Aabb)> = (0..4096u32).map(|i| (i, cube([1.0; 3], 1.0))).collect();
        let mut bvh = Bvh::new();
        bvh.build(&boxes);
        assert!(bvh.depth() <= 13, "depth {}", bvh.depth());
        check(&bvh, &boxes);
    }
}
