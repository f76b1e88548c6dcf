//! How many entries a direction's rasterisation makes at least, from the triangles' areas alone
//! and without rasterising: the figure a bake checks its `--max-bytes` ceiling, its memory and its
//! disk against before it bakes anything (a grid of tiles far finer than the triangles puts each
//! triangle in thousands of tiles, which the per-tile figures do not see).

use crate::direction::Grid;

/// The triangles' area vectors, computed once for all directions.
pub struct Areas {
    /// For each triangle: half the cross product of two edges (its dot product with a unit
    /// direction is the signed area of the triangle's projection along it), and a bound on that
    /// dot product's rounding error.
    areas: Vec<([f64; 3], f64)>,
}

/// Relative slack on the areas, far above the rounding of a cross product and a dot product in
/// f64 (a few units in 10⁻¹⁶ of the edges' lengths multiplied).
const SLACK: f64 = 1e-9;

impl Areas {
    /// The area vectors of `triangles` (three indices each into `vertices`).
    pub fn new(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Areas {
        let areas = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| vertices[k as usize]);
                let e = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let f = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [
                    0.5 * (e[1] * f[2] - e[2] * f[1]),
                    0.5 * (e[2] * f[0] - e[0] * f[2]),
                    0.5 * (e[0] * f[1] - e[1] * f[0]),
                ];
                let length = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                (n, SLACK * length(e) * length(f))
            })
            .collect();
        Areas { areas }
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.areas.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.areas.is_empty()
    }

    /// At least how many entries [`Grid::rasterize`] makes for these triangles in the direction
    /// whose rotation is `m`. The projection of a triangle onto the tile plane has the area `A`
    /// of its area vector along the direction, and lies within the tiles it touches, unit squares
    /// of side `w` (the tile width): it touches at least `⌈A / w²⌉` of them. Every triangle touches
    /// at least one, however thin.
    pub fn entries_at_least(&self, grid: &Grid, m: &[f64; 9]) -> u64 {
        let z = [m[6], m[7], m[8]];
        let w = grid.tile_width();
        let per_tile = 1.0 / (w * w);
        self.areas
            .iter()
            .map(|&(n, slack)| {
                let x = ((n[0] * z[0] + n[1] * z[1] + n[2] * z[2]).abs() - slack) * per_tile;
                // ⌈x⌉ without `f64::ceil`, a libm call on the baseline x86-64 (no SSE4.1): the
                // cast truncates, and saturates a negative `x` to 0.
                let k = x as u64;
                (k + ((k as f64) < x) as u64).max(1)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DepthPolicy;
    use crate::direction::Scratch;
    use vlf_geom::frame::frame;

    fn grid(tiles: u32) -> Grid {
        Grid { tiles, lattice_n: 4, radius: 2.0, margin: 1e-6, depth: DepthPolicy::default() }
    }

    /// Entries the rasteriser really makes, per triangle, in direction `d`.
    fn rasterised(vertices: &[[f64; 3]], triangles: &[[u32; 3]], grid: &Grid, d: [f64; 3]) -> u64 {
        let m = frame(d);
        crate::build_direction(vertices, triangles, grid, &m, &mut Scratch::default()).unwrap().stats.tile_triangle_sum
    }

    /// A pseudo-random mesh of `count` triangles inside the sphere of radius 2: large ones, small
    /// ones and degenerate ones.
    fn mesh(count: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..count {
            // Every corner within 0.5 + 0.6 of the centre on each axis: inside the grid's sphere.
            let scale = [0.6, 0.1, 0.01][i % 3];
            let c = [next() * 0.5, next() * 0.5, next() * 0.5];
            let mut corner = || [c[0] + next() * scale, c[1] + next() * scale, c[2] + next() * scale];
            let (a, b) = (corner(), corner());
            let third = if i % 7 == 0 { a } else { corner() };
            let base = vertices.len() as u32;
            vertices.extend([a, b, third]);
            triangles.push([base, base + 1, base + 2]);
        }
        (vertices, triangles)
    }

    #[test]
    fn the_bound_never_exceeds_what_the_rasteriser_makes() {
        let (vertices, triangles) = mesh(300);
        let areas = Areas::new(&vertices, &triangles);
        for tiles in [1, 4, 32, 256] {
            let g = grid(tiles);
            for d in [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.36, 0.48, 0.8], [-0.6, 0.8, 0.0]] {
                for (t, tri) in triangles.iter().enumerate() {
                    let one = Areas::new(&vertices, std::slice::from_ref(tri));
                    let made = rasterised(&vertices, std::slice::from_ref(tri), &g, d);
                    let bound = one.entries_at_least(&g, &frame(d));
                    assert!(bound <= made, "triangle {t}, {tiles}² tiles, {d:?}: bound {bound} > {made} made");
                }
                let made = rasterised(&vertices, &triangles, &g, d);
                let bound = areas.entries_at_least(&g, &frame(d));
                assert!(bound <= made && bound >= triangles.len() as u64, "{tiles}² tiles, {d:?}: {bound} vs {made}");
            }
        }
    }

    #[test]
    fn the_bound_grows_with_the_square_of_the_tiles() {
        // One triangle facing the direction, of half the grid's area: (4 × 4) / 2 in world units
        // on a 4 × 4 grid. On n² tiles it touches at least n² / 2 of them.
        let vertices = [[-2.0, -2.0, 0.0], [2.0, -2.0, 0.0], [2.0, 2.0, 0.0]];
        let areas = Areas::new(&vertices, &[[0, 1, 2]]);
        let m = frame([0.0, 0.0, 1.0]);
        for n in [1u32, 2, 16, 1024] {
            let bound = areas.entries_at_least(&grid(n), &m);
            assert_eq!(bound, (n as u64 * n as u64).div_ceil(2), "{n}² tiles");
        }
        // Seen edge on, it still touches a tile.
        assert_eq!(areas.entries_at_least(&grid(1024), &frame([1.0, 0.0, 0.0])), 1);
    }
}
