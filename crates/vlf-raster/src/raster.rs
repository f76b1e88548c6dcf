//! Conservative rasterisation of a projected triangle into the tile grid (paper §3.2, Figure 1),
//! with the box of the triangle's part in each tile's prism: its z range (paper §5) and its
//! `(u, v)` extent, which the tile's block stores quantized (`formats/vlf.md` §5.6).
//!
//! The paper walks each edge through the grid with an 8-connected traversal and fills the inside,
//! so that every tile the projected triangle touches is found, even at a corner. We get the same
//! set exactly by clipping: for each row of tiles, clip the triangle (a 3D polygon in tile
//! units) to the row's slab and take the x range of what remains; for each tile of that range,
//! clip again to the column's slab, and the box of the remaining polygon is the box of the
//! triangle's part inside the tile. Slabs are grown by the margin `e` (in tile units) so that the rounding of
//! any reader stays inside (`formats/vlf.md` §6.2). Triangles seen edge-on project to a segment;
//! clipping handles them like any other polygon, where edge functions would miss them.

/// A vertex in the canonical frame: `(u, v)` in tile units, `z` in world units.
pub type P = [f64; 3];

/// `floor` without a libm call (baseline x86-64 has no rounding instruction); exact for the
/// magnitudes here (tile coordinates, far below 2^52).
#[inline(always)]
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

#[inline(always)]
fn ceil(x: f64) -> f64 {
    -floor(-x)
}

/// A convex polygon of at most 9 vertices (a triangle clipped by 4 planes has at most 7).
#[derive(Clone, Copy)]
pub struct Poly {
    pts: [P; 9],
    len: usize,
}

impl Poly {
    pub const EMPTY: Poly = Poly { pts: [[0.0; 3]; 9], len: 0 };

    pub fn triangle(a: P, b: P, c: P) -> Self {
        let mut p = Poly::EMPTY;
        p.pts[..3].copy_from_slice(&[a, b, c]);
        p.len = 3;
        p
    }

    pub fn points(&self) -> &[P] {
        &self.pts[..self.len]
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Minimum and maximum of coordinate `axis`.
    pub fn range(&self, axis: usize) -> (f64, f64) {
        self.points().iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[axis]), hi.max(p[axis])))
    }

    /// Writes into `out` the part of the polygon with `lo ≤ p[axis] ≤ hi` (Sutherland–Hodgman
    /// against both planes in one pass over a scratch polygon).
    pub fn clip_into(&self, axis: usize, lo: f64, hi: f64, out: &mut Poly) {
        let mut mid = Poly::EMPTY;
        clip_plane(self, axis, lo, 1.0, &mut mid);
        clip_plane(&mid, axis, hi, -1.0, out);
    }

    /// The ranges of `v` and `z` over the part of the polygon with `lo ≤ u ≤ hi`, or `None` if
    /// that part is empty. The extremes of a linear function over a convex polygon clipped by a
    /// slab lie at the clipped polygon's vertices: original vertices inside the slab and the
    /// crossings of edges with the slab's planes, so no polygon is built.
    pub fn vz_ranges_in_u_slab(&self, lo: f64, hi: f64) -> Option<[(f64, f64); 2]> {
        let mut r = [(f64::INFINITY, f64::NEG_INFINITY); 2];
        let mut take = |p: P| {
            for (k, axis) in [1, 2].into_iter().enumerate() {
                r[k] = (r[k].0.min(p[axis]), r[k].1.max(p[axis]));
            }
        };
        let pts = self.points();
        for (i, &p) in pts.iter().enumerate() {
            if p[0] >= lo && p[0] <= hi {
                take(p);
            }
            let q = pts[(i + 1) % pts.len()];
            for at in [lo, hi] {
                let (dp, dq) = (p[0] - at, q[0] - at);
                if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                    let f = dp / (dp - dq);
                    take([at, p[1] + f * (q[1] - p[1]), p[2] + f * (q[2] - p[2])]);
                }
            }
        }
        (r[1].0 <= r[1].1).then_some(r)
    }
}

/// Keeps the side of `poly` where `sign · (p[axis] − at) ≥ 0`, writing to `out`.
fn clip_plane(poly: &Poly, axis: usize, at: f64, sign: f64, out: &mut Poly) {
    out.len = 0;
    let n = poly.len;
    for i in 0..n {
        let a = poly.pts[i];
        let b = poly.pts[if i + 1 == n { 0 } else { i + 1 }];
        let da = sign * (a[axis] - at);
        let db = sign * (b[axis] - at);
        if da >= 0.0 && out.len < 9 {
            out.pts[out.len] = a;
            out.len += 1;
        }
        if (da >= 0.0) != (db >= 0.0) && out.len < 9 {
            let t = da / (da - db);
            let mut p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
            p[axis] = at; // exactly on the plane
            out.pts[out.len] = p;
            out.len += 1;
        }
    }
}

/// The box of a triangle's part in one tile's grown prism: ranges of `u`, `v` (tile units) and
/// `z` (world units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    pub u: (f64, f64),
    pub v: (f64, f64),
    pub z: (f64, f64),
}

/// Calls `emit(column, row, part)` for every tile of an `n × n` grid whose closed square, grown by
/// `e` tile units on every side, meets the triangle `a, b, c`; `part` is the box of the triangle
/// inside that grown prism. Tiles are emitted row by row, columns ascending.
#[inline]
pub fn rasterize(a: P, b: P, c: P, n: u32, e: f64, mut emit: impl FnMut(u32, u32, Part)) {
    let last = n as f64 - 1.0;
    // Smallest and largest tile index whose grown closed interval [k − e, k + 1 + e] meets [lo, hi].
    let first_cell = |lo: f64| ceil(lo - e - 1.0).clamp(0.0, last) as u32;
    let last_cell = |hi: f64| floor(hi + e).clamp(0.0, last) as u32;
    let (umin, umax) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
    let (vmin, vmax) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
    let (ix0, ix1) = (first_cell(umin), last_cell(umax));
    let (iy0, iy1) = (first_cell(vmin), last_cell(vmax));
    let tri = Poly::triangle(a, b, c);
    if ix0 == ix1 && iy0 == iy1 {
        // The whole triangle lies in one tile's grown prism: no clipping needed.
        emit(ix0, iy0, Part { u: tri.range(0), v: tri.range(1), z: tri.range(2) });
        return;
    }
    let mut row = Poly::EMPTY;
    for iy in iy0..=iy1 {
        let row = if iy0 == iy1 {
            &tri
        } else {
            tri.clip_into(1, iy as f64 - e, iy as f64 + 1.0 + e, &mut row);
            &row
        };
        if row.is_empty() {
            continue;
        }
        let (ru0, ru1) = row.range(0);
        let (cx0, cx1) = (first_cell(ru0).max(ix0), last_cell(ru1).min(ix1));
        if cx0 == cx1 {
            emit(cx0, iy, Part { u: (ru0, ru1), v: row.range(1), z: row.range(2) });
            continue;
        }
        for ix in cx0..=cx1 {
            let (lo, hi) = (ix as f64 - e, ix as f64 + 1.0 + e);
            // A convex polygon's u extent clipped to a u slab is its extent cut to the slab.
            let u = (ru0.max(lo), ru1.min(hi));
            // Rounding at a corner can leave the slab empty: the row's ranges are a safe superset.
            let [v, z] = row.vz_ranges_in_u_slab(lo, hi).unwrap_or_else(|| [row.range(1), row.range(2)]);
            emit(ix, iy, Part { u, v, z });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiles_of(a: P, b: P, c: P, n: u32, e: f64) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        rasterize(a, b, c, n, e, |x, y, _| v.push((x, y)));
        v
    }

    /// Brute force: a tile is touched iff the triangle meets its grown square, decided by dense
    /// sampling of the triangle plus its vertices.
    #[test]
    fn covers_every_tile_a_dense_sampling_touches() {
        let mut state = 12345u64;
        let mut rnd = |s: f64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * s
        };
        for _ in 0..300 {
            let n = 16;
            let a = [rnd(16.0), rnd(16.0), rnd(1.0)];
            let b = [a[0] + rnd(4.0) - 2.0, a[1] + rnd(4.0) - 2.0, rnd(1.0)];
            let c = [a[0] + rnd(4.0) - 2.0, a[1] + rnd(4.0) - 2.0, rnd(1.0)];
            let got = tiles_of(a, b, c, n, 1e-9);
            for i in 0..=60 {
                for j in 0..=(60 - i) {
                    let (s, t) = (i as f64 / 60.0, j as f64 / 60.0);
                    let p = [0, 1].map(|k| a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]));
                    if p[0] < 0.0 || p[1] < 0.0 || p[0] >= 16.0 || p[1] >= 16.0 {
                        continue;
                    }
                    let cell = (p[0].floor() as u32, p[1].floor() as u32);
                    assert!(got.contains(&cell), "tile {cell:?} missing for {a:?} {b:?} {c:?}");
                }
            }
        }
    }

    /// Figure 1 of the paper: an edge passing exactly through a tile corner touches the tiles on
    /// both sides of the corner, which a DDA would miss.
    #[test]
    fn an_edge_through_a_corner_touches_all_four_tiles() {
        let got = tiles_of([0.5, 0.5, 0.0], [1.5, 1.5, 0.0], [0.5, 0.5 + 1e-6, 0.0], 4, 1e-9);
        for cell in [(0, 0), (1, 1), (0, 1), (1, 0)] {
            assert!(got.contains(&cell), "{cell:?} missing: {got:?}");
        }
    }

    #[test]
    fn an_edge_on_triangle_is_a_segment_and_still_registered() {
        // Zero projected area: all three vertices on one line in (u, v), distinct in z.
        let got = tiles_of([0.5, 0.5, 0.0], [3.5, 0.5, 1.0], [2.0, 0.5, 5.0], 4, 1e-9);
        assert_eq!(got, vec![(0, 0), (1, 0), (2, 0), (3, 0)]);
    }

    #[test]
    fn the_box_is_clipped_to_the_prism() {
        // A triangle sloping in z across tiles 0..4 of row 0: tile 1 sees only its slice, whose
        // v extent narrows as u grows (the edge from (0, 0.8) to (4, 0.2)).
        let mut parts = Vec::new();
        rasterize([0.0, 0.2, 0.0], [4.0, 0.2, 4.0], [0.0, 0.8, 0.0], 4, 0.0, |x, _, p| parts.push((x, p)));
        let (_, t1) = parts.iter().find(|r| r.0 == 1).unwrap();
        assert!(t1.z.0 >= 1.0 - 1e-12 && t1.z.1 <= 2.0 + 1e-12, "{t1:?}");
        assert!(t1.u.0 >= 1.0 - 1e-12 && t1.u.1 <= 2.0 + 1e-12, "{t1:?}");
        assert!((t1.v.0 - 0.2).abs() < 1e-12 && (t1.v.1 - 0.65).abs() < 1e-12, "{t1:?}");
    }

    /// Every sampled point of the triangle inside a tile's prism lies in that tile's box.
    #[test]
    fn every_point_in_a_tile_lies_in_its_box() {
        let mut state = 99u64;
        let mut rnd = |s: f64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * s
        };
        for _ in 0..300 {
            let a = [rnd(8.0), rnd(8.0), rnd(1.0)];
            let b = [a[0] + rnd(4.0) - 2.0, a[1] + rnd(4.0) - 2.0, rnd(1.0)];
            let c = [a[0] + rnd(4.0) - 2.0, a[1] + rnd(4.0) - 2.0, rnd(1.0)];
            let mut parts = Vec::new();
            rasterize(a, b, c, 8, 1e-9, |x, y, p| parts.push((x, y, p)));
            for i in 0..=40 {
                for j in 0..=(40 - i) {
                    let (s, t) = (i as f64 / 40.0, j as f64 / 40.0);
                    let p: [f64; 3] = std::array::from_fn(|k| a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]));
                    if p[0] < 0.0 || p[1] < 0.0 || p[0] >= 8.0 || p[1] >= 8.0 {
                        continue;
                    }
                    let (x, y) = (p[0].floor() as u32, p[1].floor() as u32);
                    let (_, _, part) = parts.iter().find(|q| q.0 == x && q.1 == y).expect("tile emitted");
                    let inside = |r: (f64, f64), v: f64| r.0 - 1e-9 <= v && v <= r.1 + 1e-9;
                    assert!(inside(part.u, p[0]) && inside(part.v, p[1]) && inside(part.z, p[2]), "{p:?} {part:?}");
                }
            }
        }
    }
}
