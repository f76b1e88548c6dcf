//! The baseline the paper measures the visibility field against (§5, §6.1): single-ray Coherent
//! Ray Tracing (Wald, Slusallek, Benthin and Wagner, Eurographics 2001), i.e. a kd-tree (axis-
//! aligned BSP tree) with spatial-median splitting planes, built to a maximum depth and a maximum
//! leaf size, traversed front to back with an explicit stack and the triangle kernel inlined.
//!
//! Everything except the acceleration structure is shared with the field runtime, so that a
//! benchmark measures the structure and nothing else: the same [`Ray`] and [`Hit`] types, the same
//! [`Intersector`] trait and the same watertight kernel ([`TriRay::intersect`]), called exactly as
//! [`vlf_geom::BruteForce`] calls it. A correct tree therefore returns the closest `t`
//! bit-identical to the brute force.
//!
//! # Robustness
//!
//! The build references a triangle in every leaf whose closed box it comes within `μ` of (a
//! relative margin of 2⁻³² of the scene's magnitude; see [`build`](KdTree::build)); the traversal
//! computes in f64, whose rounding stays far below `μ`, so the leaves a query visits can only hold
//! *more* candidates than exact arithmetic would give, never fewer. Rays parallel to an axis (a
//! zero direction component, where `0 · ∞` would give NaN) and rays lying exactly in a splitting
//! plane are handled explicitly: such a ray visits one child, which suffices because every point
//! on the plane belongs to both closed child boxes.
//!
//! Queries allocate nothing: the traversal stack is a fixed array of [`MAX_DEPTH`] entries.

#![forbid(unsafe_code)]

mod build;
mod tree;

pub use tree::{KdNode, KdParams, KdTree, KdTreeStats, MAX_DEPTH, MAX_LINK};
use vlf_geom::{Baseline, Closest, Hit, Intersector, Ray, TriRay};
pub use vlf_geom::{Counter, TraceStats};

/// One traversal stack entry: a node still to visit and its ray-parameter interval.
#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    t0: f64,
    t1: f64,
}

impl KdTree {
    /// Builds the tree (see the crate docs and `docs/kdtree.md`). Each node's box is split at
    /// the midpoint of its longest axis; a node becomes a leaf at `params.max_depth`, when it
    /// holds at most `params.leaf_size` references, or when the split would send every reference
    /// to both children. A triangle straddling the plane goes to both children, to each only if
    /// the triangle clipped to the child's box (grown by the margin) is not empty. Deterministic:
    /// the same input gives the same tree, whatever the thread count. Parallel over subtrees.
    pub fn build(triangles: &[[[f32; 3]; 3]], params: KdParams) -> KdTree {
        build::build(triangles, params)
    }

    /// The tree of triangles given relative to `origin` (as a field stores them), queried with
    /// rays in world coordinates: the ray is moved by `−origin` in f64, as the field and
    /// `vlf_geom::BruteForce::relative` move it, so the three answer alike.
    pub fn relative_to(mut self, origin: [f64; 3]) -> KdTree {
        self.origin = origin;
        self
    }

    /// The parameters the tree was built with (depth clamped to [`MAX_DEPTH`]).
    pub fn params(&self) -> KdParams {
        self.params
    }

    /// The scene's bounding box (exact, over all input vertices), or `None` for an empty tree.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        self.bounds
    }

    /// The margin `μ` by which the build grew every triangle's reach (2⁻³² of the scene's
    /// largest coordinate magnitude).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// The nodes; the root is `nodes()[0]`.
    pub fn nodes(&self) -> &[KdNode] {
        &self.nodes
    }

    /// Input indices of the triangles referenced by leaf `node` (empty for an inner node).
    pub fn leaf_triangles(&self, node: usize) -> impl Iterator<Item = u32> + '_ {
        let n = self.nodes[node];
        let range = if n.is_leaf() { n.references() } else { 0..0 };
        self.references[range].iter().map(|&i| self.prims[i as usize])
    }

    /// Size and shape of the tree.
    pub fn stats(&self) -> KdTreeStats {
        let leaves = self.nodes.iter().filter(|n| n.is_leaf());
        let empty = leaves.clone().filter(|n| n.references().is_empty()).count();
        let bytes = self.nodes.capacity() * size_of::<KdNode>()
            + self.references.capacity() * size_of::<u32>()
            + self.triangles.capacity() * size_of::<[[f32; 3]; 3]>()
            + self.prims.capacity() * size_of::<u32>();
        KdTreeStats {
            nodes: self.nodes.len() as u64,
            leaves: leaves.count() as u64,
            empty_leaves: empty as u64,
            max_depth: self.max_depth_reached,
            references: self.references.len() as u64,
            triangles: self.triangles.len() as u64,
            bytes: bytes as u64,
        }
    }

    /// The closest hit on `[tmin, tmax]`, if any.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.trace::<false, _>(ray, self.origin, &mut ())
    }

    /// [`Self::closest_hit`], counting the work done into `stats`.
    pub fn closest_hit_counted(&self, ray: &Ray, stats: &mut TraceStats) -> Option<Hit> {
        self.trace::<false, _>(ray, self.origin, stats)
    }

    /// Whether anything is hit on `[tmin, tmax]`; the first hit found ends the search.
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.trace::<true, _>(ray, self.origin, &mut ()).is_some()
    }

    /// The first hit found on `[tmin, tmax]` (not necessarily the closest), counting the work.
    pub fn any_hit_counted(&self, ray: &Ray, stats: &mut TraceStats) -> Option<Hit> {
        self.trace::<true, _>(ray, self.origin, stats)
    }

    /// [`Self::closest_hit_counted`] for a ray whose origin is given relative to the tree's
    /// origin ([`Self::relative_to`]; the world's origin for a tree of world triangles).
    pub fn closest_hit_local_counted(&self, ray: &Ray, stats: &mut TraceStats) -> Option<Hit> {
        self.trace::<false, _>(ray, [0.0; 3], stats)
    }

    /// [`Self::any_hit_counted`] for a ray given relative to the tree's origin.
    pub fn any_hit_local_counted(&self, ray: &Ray, stats: &mut TraceStats) -> Option<Hit> {
        self.trace::<true, _>(ray, [0.0; 3], stats)
    }

    /// `hit` with its `prim` turned from an index into the tree's triangles into the caller's id.
    #[inline(always)]
    fn original(&self, hit: Hit) -> Hit {
        Hit { prim: self.prims[hit.prim as usize], ..hit }
    }

    /// The traversal, generic over what it counts and over whether the first hit ends it, of
    /// `ray` moved by `−origin` into the triangles' frame (the tree's origin for a world ray, zero
    /// for a local one).
    #[inline(always)]
    fn trace<const ANY: bool, C: Counter>(&self, ray: &Ray, origin: [f64; 3], counter: &mut C) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let (lo, hi) = self.root?;
        let o: [f64; 3] = std::array::from_fn(|i| ray.org[i] as f64 - origin[i]);
        // `+ 0.0` turns −0 into +0, so a zero component always gives +∞ and "positive" below.
        let inv = ray.dir.map(|d| 1.0 / (d as f64 + 0.0));
        // Clip to the (grown) scene box. An axis the ray is parallel to only tests the origin.
        let mut t0 = ray.tmin as f64;
        let mut t1 = ray.tmax as f64;
        for k in 0..3 {
            if inv[k].is_infinite() {
                if o[k] < lo[k] || o[k] > hi[k] {
                    return None;
                }
            } else {
                let a = (lo[k] - o[k]) * inv[k];
                let b = (hi[k] - o[k]) * inv[k];
                let (near, far) = if inv[k] < 0.0 { (b, a) } else { (a, b) };
                t0 = t0.max(near);
                t1 = t1.min(far);
            }
        }
        // (Neither can be NaN: the bounds are finite and `max`/`min` drop NaN operands.)
        if t0 > t1 {
            return None;
        }
        counter.ray();

        let tri_ray = TriRay::relative(ray, origin);
        let tris = &self.triangles[..];
        let mut best = Closest::new(ray.tmax);
        let mut stack = [Entry { node: 0, t0: 0.0, t1: 0.0 }; MAX_DEPTH as usize];
        let mut sp = 0usize;
        let mut node = 0usize;
        loop {
            counter.cell();
            let n = self.nodes[node];
            if !n.is_leaf() {
                let k = n.axis();
                // (s − o)·(1/d): ±∞ when the ray is parallel to the plane, NaN when it also lies
                // in it. Near is the child the ray enters first.
                let ts = (n.split() as f64 - o[k]) * inv[k];
                let first = n.first_child();
                let (near, far) = if inv[k] < 0.0 { (first + 1, first) } else { (first, first + 1) };
                if ts > t1 || ts.is_nan() {
                    // Crosses the plane after the interval (or never, or lies in it: then either
                    // closed child contains the whole ray and every triangle the ray can hit).
                    node = near;
                } else if ts < t0 {
                    node = far;
                } else {
                    stack[sp] = Entry { node: far as u32, t0: ts, t1 };
                    sp += 1;
                    node = near;
                    t1 = ts;
                }
                continue;
            }

            counter.leaf();
            let ids = self.references[n.references()].iter().copied();
            if ANY {
                if let Some(hit) = tri_ray.any_in(Baseline, tris, ids, counter) {
                    return Some(self.original(hit));
                }
            } else {
                tri_ray.closest_in(Baseline, tris, ids, &mut best, counter);
            }
            // Final once the best hit lies within the part of the ray already searched.
            if (best.hit.is_some() && best.tmax as f64 <= t1) || sp == 0 {
                return best.hit.map(|hit| self.original(hit));
            }
            sp -= 1;
            let e = stack[sp];
            node = e.node as usize;
            t0 = e.t0;
            t1 = e.t1;
        }
    }
}

impl Intersector for KdTree {
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        KdTree::closest_hit(self, ray)
    }

    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        KdTree::any_hit(self, ray)
    }

    #[inline]
    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        KdTree::closest_hit_counted(self, ray, work)
    }

    #[inline]
    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        KdTree::any_hit_counted(self, ray, work)
    }

    fn origin(&self) -> [f64; 3] {
        self.origin
    }

    #[inline]
    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        KdTree::closest_hit_local_counted(self, ray, work)
    }

    #[inline]
    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        KdTree::any_hit_local_counted(self, ray, work)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vlf_geom::BruteForce;

    fn assert_send_sync<T: Send + Sync>() {}

    #[test]
    fn tree_is_send_and_sync_and_nodes_are_8_bytes() {
        assert_send_sync::<KdTree>();
        assert_eq!(size_of::<KdNode>(), 8);
    }

    #[test]
    fn node_encoding_round_trips() {
        let n = KdNode::inner(2, -1.5, 12345);
        assert!(!n.is_leaf());
        assert_eq!((n.axis(), n.split(), n.first_child()), (2, -1.5, 12345));
        let l = KdNode::leaf(MAX_LINK, 7);
        assert!(l.is_leaf());
        assert_eq!(l.references(), MAX_LINK as usize..MAX_LINK as usize + 7);
    }

    #[test]
    fn empty_tree_misses() {
        let tree = KdTree::build(&[], KdParams::default());
        let ray = Ray::new([0.0; 3], [1.0, 0.0, 0.0]);
        assert_eq!(tree.closest_hit(&ray), None);
        assert!(!tree.any_hit(&ray));
        assert_eq!(tree.stats().nodes, 1);
        assert_eq!(tree.bounds(), None);
    }

    #[test]
    fn quad_matches_brute_force_along_its_split_planes() {
        let q = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let tree = KdTree::build(&tris, KdParams { max_depth: 8, leaf_size: 1 });
        let bf = BruteForce::new(&tris);
        for i in 0..=16 {
            for j in 0..=16 {
                let (x, y) = (i as f32 / 16.0, j as f32 / 16.0);
                for ray in [
                    Ray::new([x, y, 1.0], [0.0, 0.0, -1.0]),
                    Ray::new([x, y, -1.0], [0.0, -0.0, 2.0]),
                    Ray::new([x, -1.0, 0.5], [0.0, 1.0, -0.25]),
                ] {
                    assert_eq!(tree.closest_hit(&ray).map(|h| h.t), bf.closest_hit(&ray).map(|h| h.t), "{ray:?}");
                    assert_eq!(tree.any_hit(&ray), bf.any_hit(&ray), "{ray:?}");
                }
            }
        }
    }

    /// Local rays (relative to the tree's origin) keep a scene's precision however far it is:
    /// the quad at x = 10⁹, where f32 world coordinates are 64 apart, is hit where a local ray
    /// aims, as brute force over the same relative triangles hits it.
    #[test]
    fn local_rays_of_a_far_quad_match_brute_force() {
        let q = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let tris = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
        let far = [1e9, 0.0, 0.0];
        let tree = KdTree::build(&tris, KdParams { max_depth: 8, leaf_size: 1 }).relative_to(far);
        let bf = BruteForce::relative(&tris, far);
        assert_eq!((Intersector::origin(&tree), Intersector::origin(&bf)), (far, far));
        let mut work = TraceStats::default();
        for i in 0..=16 {
            let x = i as f32 / 16.0;
            let ray = Ray::new([x, 0.5, 1.0], [0.0, 0.0, -1.0]);
            let hit = tree.closest_hit_local_counted(&ray, &mut work);
            assert_eq!(hit.map(|h| h.t), Some(1.0), "{ray:?}");
            assert_eq!(hit, bf.closest_hit_local_counted(&ray, &mut work), "{ray:?}");
            let any = Intersector::any_hit_local_counted(&tree, &ray, &mut work).is_some();
            assert_eq!((any, bf.any_hit_local_counted(&ray, &mut work).is_some()), (true, true), "{ray:?}");
        }
        // A ray beside the quad misses in both.
        let beside = Ray::new([1.25, 0.5, 1.0], [0.0, 0.0, -1.0]);
        assert_eq!(tree.closest_hit_local_counted(&beside, &mut work), None);
        assert_eq!(bf.closest_hit_local_counted(&beside, &mut work), None);
    }
}
