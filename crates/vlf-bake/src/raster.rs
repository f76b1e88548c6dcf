//! Conservative rasterisation of a projected triangle into the tile grid (paper §3.2, Figure 1),
//! with each tile's z range from clipping the triangle to the tile's prism (paper §5).
//!
//! The paper walks each edge through the grid with an 8-connected traversal and fills the inside,
//! so that every tile the projected triangle touches is found, even at a corner. We get the same
//! set exactly by clipping: for each row of tiles, clip the triangle (a 3D polygon in tile
//! units) to the row's slab and take the x range of what remains; for each tile of that range,
//! clip again to the column's slab, and the z range of the remaining polygon is the triangle's z
//! range inside the tile. Slabs are grown by the margin `e` (in tile units) so that the rounding of
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

    /// The range of `z` over the part of the polygon with `lo ≤ p[axis] ≤ hi`, or `None` if that
    /// part is empty. The extremes of a linear function over a convex polygon clipped by a slab lie
    /// at the clipped polygon's vertices: original vertices inside the slab and the crossings of
    /// edges with the slab's planes, so no polygon is built.
    pub fn z_range_in_slab(&self, axis: usize, lo: f64, hi: f64) -> Option<(f64, f64)> {
        let (mut zmin, mut zmax) = (f64::INFINITY, f64::NEG_INFINITY);
        let pts = self.points();
        for (i, &p) in pts.iter().enumerate() {
            if p[axis] >= lo && p[axis] <= hi {
                zmin = zmin.min(p[2]);
                zmax = zmax.max(p[2]);
            }
            let q = pts[(i + 1) % pts.len()];
            for at in [lo, hi] {
                let (dp, dq) = (p[axis] - at, q[axis] - at);
                if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                    let z = p[2] + dp / (dp - dq) * (q[2] - p[2]);
                    zmin = zmin.min(z);
                    zmax = zmax.max(z);
                }
            }
        }
        (zmin <= zmax).then_some((zmin, zmax))
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

/// Calls `emit(column, row, z_lo, z_hi)` for every tile of an `n × n` grid whose closed square,
/// grown by `e` tile units on every side, meets the triangle `a, b, c`; `z_lo..z_hi` is the z range
/// of the triangle inside that grown prism. Tiles are emitted row by row, columns ascending.
#[inline]
pub fn rasterize(a: P, b: P, c: P, n: u32, e: f64, mut emit: impl FnMut(u32, u32, f64, f64)) {
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
        let (z0, z1) = tri.range(2);
        emit(ix0, iy0, z0, z1);
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
            let (z0, z1) = row.range(2);
            emit(cx0, iy, z0, z1);
            continue;
        }
        for ix in cx0..=cx1 {
            // Rounding at a corner can leave the slab empty: the row's range is a safe superset.
            let (z0, z1) = row.z_range_in_slab(0, ix as f64 - e, ix as f64 + 1.0 + e).unwrap_or_else(|| row.range(2));
            emit(ix, iy, z0, z1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiles_of(a: P, b: P, c: P, n: u32, e: f64) -> Vec<(u32, u32)> {
        let mut v = Vec::new();
        rasterize(a, b, c, n, e, |x, y, _, _| v.push((x, y)));
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
    fn z_range_is_clipped_to_the_prism() {
        // A triangle sloping in z across tiles 0..4 of row 0: tile 1 sees only its slice.
        let mut ranges = Vec::new();
        rasterize([0.0, 0.2, 0.0], [4.0, 0.2, 4.0], [0.0, 0.8, 0.0], 4, 0.0, |x, _, z0, z1| ranges.push((x, z0, z1)));
        let t1 = ranges.iter().find(|r| r.0 == 1).unwrap();
        assert!(t1.1 >= 1.0 - 1e-12 && t1.2 <= 2.0 + 1e-12, "{t1:?}");
    }
}
