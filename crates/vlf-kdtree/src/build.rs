//! Construction: spatial-median splits with reference duplication, straddling triangles clipped
//! to each child's box ("split clipping") so that a triangle only reaches the leaves it touches.
//!
//! Each reference carries the bounding box of its triangle clipped to the current node's box
//! grown by the margin `μ`, rounded outward to f32. A split at `s` on axis `k` sends a reference
//! to the lower child if its box reaches `s + μ`, to the upper child if it reaches `s − μ`; for a
//! reference that goes both ways the triangle is clipped to the reference's box again and the
//! polygon cut at `s + μ` and `s − μ` gives the two children's boxes. Every step only ever grows
//! the boxes (the margin `μ` dwarfs the f64 rounding of the clip; boxes are rounded outward to
//! f32), so a triangle is referenced in every leaf whose closed box it comes within `μ` of, and
//! perhaps in a few more.

use crate::tree::{KdNode, KdParams, KdTree, MAX_DEPTH, MAX_LINK};

type Tri = [[f32; 3]; 3];

/// Nodes with more references than this build their two subtrees in parallel.
const PARALLEL_REFS: usize = 2048;

/// One triangle reference during the build: the triangle and its clipped bounding box.
#[derive(Clone, Copy, Debug)]
struct Ref {
    id: u32,
    lo: [f32; 3],
    hi: [f32; 3],
}

/// The tree before it is laid out.
enum Tmp {
    Leaf(Vec<u32>),
    Inner { axis: usize, split: f32, kids: Box<(Tmp, Tmp)> },
}

struct Ctx<'a> {
    tris: &'a [Tri],
    params: KdParams,
    mu: f64,
}

pub(crate) fn build(triangles: &[Tri], params: KdParams) -> KdTree {
    assert!(triangles.len() <= MAX_LINK as usize, "kd-tree: more than 2^30 triangles");
    let params = KdParams { max_depth: params.max_depth.min(MAX_DEPTH), leaf_size: params.leaf_size };
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut magnitude = 0f64;
    let refs: Vec<Ref> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (tl, th) = tri_bounds(t);
            for k in 0..3 {
                lo[k] = lo[k].min(tl[k]);
                hi[k] = hi[k].max(th[k]);
                magnitude = magnitude.max((tl[k] as f64).abs()).max((th[k] as f64).abs());
            }
            Ref { id: i as u32, lo: tl, hi: th }
        })
        .collect();
    if refs.is_empty() {
        return KdTree {
            params,
            nodes: vec![KdNode::leaf(0, 0)],
            references: Vec::new(),
            triangles: Vec::new(),
            prims: Vec::new(),
            root: None,
            bounds: None,
            margin: 0.0,
            max_depth_reached: 0,
            origin: [0.0; 3],
        };
    }
    // 2⁻³² of the scene's magnitude: far above the f64 rounding of clipping and traversal (about
    // 2⁻⁵² of the magnitudes involved), far below anything an f32 scene can resolve (2⁻²⁴).
    let mu = magnitude * (-32f64).exp2();
    let ctx = Ctx { tris: triangles, params, mu };
    let root = build_node(&ctx, refs, lo, hi, 0);

    // Lay out depth first, the two children of a node adjacent, leaves' lists in visit order.
    let mut nodes = vec![KdNode::leaf(0, 0)];
    let mut references: Vec<u32> = Vec::new();
    let mut max_depth_reached = 0;
    let mut work = vec![(root, 0usize, 0u32)];
    while let Some((tmp, index, depth)) = work.pop() {
        match tmp {
            Tmp::Leaf(ids) => {
                max_depth_reached = max_depth_reached.max(depth);
                nodes[index] = KdNode::leaf(references.len() as u32, ids.len() as u32);
                references.extend_from_slice(&ids);
                assert!(references.len() <= MAX_LINK as usize, "kd-tree: more than 2^30 references");
            }
            Tmp::Inner { axis, split, kids } => {
                let first = nodes.len();
                nodes[index] = KdNode::inner(axis, split, first as u32);
                nodes.extend([KdNode::leaf(0, 0); 2]);
                let (l, r) = *kids;
                work.push((r, first + 1, depth + 1));
                work.push((l, first, depth + 1));
            }
        }
    }

    // Store the triangles in order of first reference, for locality.
    let mut slot = vec![u32::MAX; triangles.len()];
    let mut stored = Vec::new();
    let mut prims = Vec::new();
    for r in &mut references {
        let id = *r as usize;
        if slot[id] == u32::MAX {
            slot[id] = stored.len() as u32;
            stored.push(triangles[id]);
            prims.push(id as u32);
        }
        *r = slot[id];
    }
    let grow = |v: f32, s: f64| v as f64 + s * mu;
    KdTree {
        params,
        nodes,
        references,
        triangles: stored,
        prims,
        root: Some((lo.map(|v| grow(v, -1.0)), hi.map(|v| grow(v, 1.0)))),
        bounds: Some((lo, hi)),
        margin: mu,
        max_depth_reached,
        origin: [0.0; 3],
    }
}

fn tri_bounds(t: &Tri) -> ([f32; 3], [f32; 3]) {
    let lo = std::array::from_fn(|k| t[0][k].min(t[1][k]).min(t[2][k]));
    let hi = std::array::from_fn(|k| t[0][k].max(t[1][k]).max(t[2][k]));
    (lo, hi)
}

fn leaf(refs: Vec<Ref>) -> Tmp {
    // Not `into_iter().collect()`: that would reuse (and keep) the possibly much larger buffer.
    let mut ids = Vec::with_capacity(refs.len());
    ids.extend(refs.iter().map(|r| r.id));
    Tmp::Leaf(ids)
}

fn build_node(ctx: &Ctx, refs: Vec<Ref>, lo: [f32; 3], hi: [f32; 3], depth: u32) -> Tmp {
    let n = refs.len();
    if depth >= ctx.params.max_depth || n <= ctx.params.leaf_size as usize {
        return leaf(refs);
    }
    // The spatial median of the longest axis (the first of equal ones).
    let extent = |k: usize| hi[k] as f64 - lo[k] as f64;
    let k = if extent(0) >= extent(1) && extent(0) >= extent(2) {
        0
    } else if extent(1) >= extent(2) {
        1
    } else {
        2
    };
    let s = ((lo[k] as f64 + hi[k] as f64) * 0.5) as f32;
    if !(lo[k] < s && s < hi[k]) {
        // The box is a single float wide: nothing left to split.
        return leaf(refs);
    }
    let (s64, mu) = (s as f64, ctx.mu);
    let goes_low = |r: &Ref| r.lo[k] as f64 <= s64 + mu;
    let goes_high = |r: &Ref| r.hi[k] as f64 >= s64 - mu;
    let n_low = refs.iter().filter(|r| goes_low(r)).count();
    let n_high = refs.iter().filter(|r| goes_high(r)).count();
    if n_low == n && n_high == n {
        // Every triangle straddles the plane: splitting would only duplicate them.
        return leaf(refs);
    }

    // The lower child reuses the node's buffer (each reference read writes at most one lower
    // reference, so writes never overtake reads); the upper child gets its own.
    let mut low = refs;
    let mut high = Vec::with_capacity(n_high);
    let mut w = 0;
    let (mut poly_a, mut poly_b) = ([[0f64; 3]; CAP], [[0f64; 3]; CAP]);
    for i in 0..n {
        let r = low[i];
        match (goes_low(&r), goes_high(&r)) {
            (true, false) => {
                low[w] = r;
                w += 1;
            }
            (false, true) => high.push(r),
            _ => {
                let (l, h) = split_clip(&ctx.tris[r.id as usize], &r, k, s64, mu, &mut poly_a, &mut poly_b);
                if let Some(c) = l {
                    low[w] = c;
                    w += 1;
                }
                if let Some(c) = h {
                    high.push(c);
                }
            }
        }
    }
    low.truncate(w);
    let mut low_hi = hi;
    low_hi[k] = s;
    let mut high_lo = lo;
    high_lo[k] = s;
    let (a, b) = if n > PARALLEL_REFS {
        rayon::join(|| build_node(ctx, low, lo, low_hi, depth + 1), || build_node(ctx, high, high_lo, hi, depth + 1))
    } else {
        (build_node(ctx, low, lo, low_hi, depth + 1), build_node(ctx, high, high_lo, hi, depth + 1))
    };
    Tmp::Inner { axis: k, split: s, kids: Box::new((a, b)) }
}

/// Room for a clipped triangle: a convex polygon gains at most one vertex per plane (3 + 6), and
/// rounding could in principle make it slightly non-convex, so twice that; a polygon that would
/// outgrow it is replaced by the (conservative) box of the whole triangle.
const CAP: usize = 18;

type Poly = [[f64; 3]; CAP];

/// Clips `tri` to the box `[lo, hi]` (Sutherland–Hodgman in f64) and returns the polygon's
/// length (0 if the triangle misses the box, `None` if it outgrew the buffers); the polygon ends
/// up in `a`.
///
/// The side of a plane a vertex lies on is exact (the sign of a difference of floats is), and the
/// points the clip creates lie on the box, so rounding only moves new vertices along its faces.
fn clip_polygon(tri: &Tri, lo: [f64; 3], hi: [f64; 3], a: &mut Poly, b: &mut Poly) -> Option<usize> {
    let (mut cur, mut nxt) = (a, b);
    for (p, v) in cur.iter_mut().zip(tri) {
        *p = v.map(f64::from);
    }
    let mut len = 3;
    let mut swapped = false;
    for plane in 0..6 {
        let k = plane >> 1;
        // Signed distance (up to scale) from the plane, non-negative inside.
        let dist = |p: &[f64; 3]| if plane & 1 == 0 { p[k] - lo[k] } else { hi[k] - p[k] };
        if cur[..len].iter().all(|p| dist(p) >= 0.0) {
            continue;
        }
        if 2 * len > CAP {
            return None;
        }
        let bound = if plane & 1 == 0 { lo[k] } else { hi[k] };
        let mut m = 0;
        let mut prev = cur[len - 1];
        let mut d_prev = dist(&prev);
        for &p in &cur[..len] {
            let d = dist(&p);
            if (d_prev >= 0.0) != (d >= 0.0) {
                let t = d_prev / (d_prev - d);
                let mut q: [f64; 3] = std::array::from_fn(|j| prev[j] + t * (p[j] - prev[j]));
                q[k] = bound;
                nxt[m] = q;
                m += 1;
            }
            if d >= 0.0 {
                nxt[m] = p;
                m += 1;
            }
            prev = p;
            d_prev = d;
        }
        if m == 0 {
            return Some(0);
        }
        std::mem::swap(&mut cur, &mut nxt);
        swapped = !swapped;
        len = m;
    }
    if swapped {
        nxt[..len].copy_from_slice(&cur[..len]);
    }
    Some(len)
}

/// Outward-rounded f32 box of f64 bounds, clamped to `[lo, hi]`.
fn to_ref(id: u32, a: [f64; 3], b: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Ref {
    Ref {
        id,
        lo: std::array::from_fn(|k| round_down(a[k].max(lo[k]))),
        hi: std::array::from_fn(|k| round_up(b[k].min(hi[k]))),
    }
}

/// Splits reference `r` (its triangle clipped to its box) by the slab `s ± μ` on axis `k`: the
/// clipped boxes of the part at most `s + μ` and of the part at least `s − μ`, rounded outward.
#[allow(clippy::too_many_arguments)]
fn split_clip(tri: &Tri, r: &Ref, k: usize, s: f64, mu: f64, a: &mut Poly, b: &mut Poly) -> (Option<Ref>, Option<Ref>) {
    let lo = r.lo.map(f64::from);
    let hi = r.hi.map(f64::from);
    let (cut_low, cut_high) = (s + mu, s - mu);
    let mut low_hi = hi;
    low_hi[k] = low_hi[k].min(cut_low);
    let mut high_lo = lo;
    high_lo[k] = high_lo[k].max(cut_high);
    let Some(len) = clip_polygon(tri, lo, hi, a, b) else {
        // Pathological rounding: fall back to the triangle's box.
        let (tl, th) = tri_bounds(tri);
        let (tl, th) = (tl.map(f64::from), th.map(f64::from));
        return (Some(to_ref(r.id, tl, th, lo, low_hi)), Some(to_ref(r.id, tl, th, high_lo, hi)));
    };
    let poly = &a[..len];
    let mut bl = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut bh = bl;
    let add = |bx: &mut ([f64; 3], [f64; 3]), p: &[f64; 3]| {
        for ((lo, hi), &v) in bx.0.iter_mut().zip(&mut bx.1).zip(p) {
            *lo = lo.min(v);
            *hi = hi.max(v);
        }
    };
    for i in 0..len {
        let p = &poly[i];
        let q = &poly[if i + 1 == len { 0 } else { i + 1 }];
        if p[k] <= cut_low {
            add(&mut bl, p);
        }
        if p[k] >= cut_high {
            add(&mut bh, p);
        }
        // Where the edge p→q crosses a cut, the crossing point belongs to that side.
        for (cut, bx) in [(cut_low, &mut bl), (cut_high, &mut bh)] {
            let (dp, dq) = (p[k] - cut, q[k] - cut);
            if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                let t = dp / (dp - dq);
                let mut x: [f64; 3] = std::array::from_fn(|j| p[j] + t * (q[j] - p[j]));
                x[k] = cut;
                add(bx, &x);
            }
        }
    }
    let side = |bx: ([f64; 3], [f64; 3]), lo, hi| (bx.0[0] <= bx.1[0]).then(|| to_ref(r.id, bx.0, bx.1, lo, hi));
    (side(bl, lo, low_hi), side(bh, high_lo, hi))
}

/// The largest f32 at most `x`.
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { next_toward_neg_inf(f) } else { f }
}

/// The smallest f32 at least `x`.
fn round_up(x: f64) -> f32 {
    -round_down(-x)
}

fn next_toward_neg_inf(f: f32) -> f32 {
    if f == 0.0 {
        -f32::from_bits(1)
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outward_rounding() {
        for x in [0.1f64, -0.1, 1.0, -1.0, 0.0, 1e-40, -1e-40, 3.0e38] {
            let (d, u) = (round_down(x), round_up(x));
            assert!((d as f64) <= x && (u as f64) >= x, "{x}");
            assert!(u == d || next_toward_neg_inf(u) == d, "{x}");
        }
    }

    #[test]
    fn clipping_keeps_touching_triangles() {
        let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let (mut a, mut b) = ([[0f64; 3]; CAP], [[0f64; 3]; CAP]);
        let r = Ref { id: 0, lo: [0.0; 3], hi: [1.0, 1.0, 0.0] };
        // Split at x = 1 (touching at one vertex only) and x = 0.5 (the hypotenuse crosses it
        // at y = 0.5).
        let (l, h) = split_clip(&tri, &r, 0, 1.0, 0.0, &mut a, &mut b);
        assert_eq!(l.map(|r| (r.lo, r.hi)), Some(([0.0; 3], [1.0, 1.0, 0.0])));
        assert_eq!(h.map(|r| (r.lo, r.hi)), Some(([1.0, 0.0, 0.0], [1.0, 0.0, 0.0])));
        let (l, h) = split_clip(&tri, &r, 0, 0.5, 0.0, &mut a, &mut b);
        assert_eq!(l.map(|r| (r.lo, r.hi)), Some(([0.0; 3], [0.5, 1.0, 0.0])));
        assert_eq!(h.map(|r| (r.lo, r.hi)), Some(([0.5, 0.0, 0.0], [1.0, 0.5, 0.0])));
        // The reference's box cuts the triangle off at y ≥ 0.75: nothing left beyond x = 0.5.
        let r = Ref { id: 0, lo: [0.0, 0.75, 0.0], hi: [1.0, 1.0, 0.0] };
        let (l, h) = split_clip(&tri, &r, 0, 0.5, 0.0, &mut a, &mut b);
        assert_eq!(l.map(|r| (r.lo, r.hi)), Some(([0.0, 0.75, 0.0], [0.25, 1.0, 0.0])));
        assert!(h.is_none());
    }
}
