//! How many entries a direction's rasterisation makes at least, from the triangles' areas alone
//! and without rasterising: the figure a bake checks its `--max-bytes` ceiling, its memory and its
//! disk against before it bakes anything (a grid of tiles far finer than the triangles puts each
//! triangle in thousands of tiles, which the per-tile figures do not see).

use crate::direction::Grid;

/// What bounds a triangle's tiles in any direction, computed once for all directions.
#[derive(Clone, Copy)]
struct Measures {
    /// Half the cross product of two edges: its dot product with a unit direction is the signed
    /// area of the triangle's projection along it.
    area: [f64; 3],
    /// A bound on that dot product's rounding error.
    slack: f64,
    /// The longest edge, and its squared length.
    edge: [f64; 3],
    edge2: f64,
}

/// The triangles' area vectors and longest edges, computed once for all directions.
pub struct Areas {
    triangles: Vec<Measures>,
}

/// Relative slack on the areas, far above the rounding of a cross product and a dot product in
/// f64 (a few units in 10⁻¹⁶ of the edges' lengths multiplied).
const SLACK: f64 = 1e-9;

impl Areas {
    /// The area vectors of `triangles` (three indices each into `vertices`).
    pub fn new(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Areas {
        let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        let dot = |v: [f64; 3], w: [f64; 3]| v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
        let triangles = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| vertices[k as usize]);
                let (e, f, g) = (sub(b, a), sub(c, a), sub(c, b));
                let area = [
                    0.5 * (e[1] * f[2] - e[2] * f[1]),
                    0.5 * (e[2] * f[0] - e[0] * f[2]),
                    0.5 * (e[0] * f[1] - e[1] * f[0]),
                ];
                let slack = SLACK * (dot(e, e) * dot(f, f)).sqrt();
                let (edge, edge2) = [e, f, g]
                    .into_iter()
                    .map(|v| (v, dot(v, v)))
                    .fold(([0.0; 3], 0.0), |m, x| if x.1 > m.1 { x } else { m });
                Measures { area, slack, edge, edge2 }
            })
            .collect();
        Areas { triangles }
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// At least how many entries [`Grid::rasterize`] makes for these triangles in the direction
    /// whose rotation is `m`, on tiles of side `w`. A triangle's projection touches at least:
    ///
    /// - `⌈A / w²⌉` tiles, `A` its area (the area of the triangle's area vector along the
    ///   direction): it lies within the tiles it touches;
    /// - `⌊L / (w√2)⌋ + 1` tiles, `L` the length of its longest edge's projection: the edge spans
    ///   `L / √2` or more along one of the grid's axes, and a connected set spanning `X` tile
    ///   widths along an axis touches `⌊X⌋ + 1` or more columns (or rows) of tiles, one tile in
    ///   each at least. This one counts long thin triangles, whose area says little.
    ///
    /// Every triangle touches at least one tile, however small.
    pub fn entries_at_least(&self, grid: &Grid, m: &[f64; 9]) -> u64 {
        let z = [m[6], m[7], m[8]];
        let w = grid.tile_width();
        let per_tile = 1.0 / (w * w);
        let per_width = 1.0 / (w * std::f64::consts::SQRT_2);
        // ⌈x⌉ and ⌊x⌋ without `f64::ceil` or `f64::floor`, libm calls on the baseline x86-64 (no
        // SSE4.1): the cast truncates, and saturates a negative `x` to 0.
        let ceil = |x: f64| {
            let k = x as u64;
            k + ((k as f64) < x) as u64
        };
        self.triangles
            .iter()
            .map(|t| {
                let dot = |v: [f64; 3]| v[0] * z[0] + v[1] * z[1] + v[2] * z[2];
                let by_area = ceil((dot(t.area).abs() - t.slack) * per_tile);
                let along = dot(t.edge);
                // The projected length, shortened by the same relative slack.
                let length = (t.edge2 - along * along).max(0.0).sqrt() * (1.0 - SLACK);
                let by_length = (length * per_width) as u64 + 1;
                by_area.max(by_length)
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
        crate::build_direction(vertices, triangles, grid, &m, &mut Scratch::default(), crate::MAX_WORDS, None)
            .unwrap()
            .stats
            .tile_triangle_sum
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
        // Seen edge on, it is a segment 4 units (1024 tile widths) long; its longest edge, whose
        // direction the bound does not know, is counted at 1024 / √2 widths along one axis.
        let edge_on = frame([1.0, 0.0, 0.0]);
        assert_eq!(areas.entries_at_least(&grid(1024), &edge_on), 725);
        assert!(725 <= rasterised(&vertices, &[[0, 1, 2]], &grid(1024), [1.0, 0.0, 0.0]));
    }

    #[test]
    fn a_direction_past_its_word_limit_stops_naming_it() {
        // The limit a direction's blocks may take is checked as the refs are sorted into leaves:
        // exactly its words pass, one word fewer does not.
        let (vertices, triangles) = mesh(300);
        let (g, m) = (grid(32), frame([0.36, 0.48, 0.8]));
        let words =
            crate::build_direction(&vertices, &triangles, &g, &m, &mut Scratch::default(), crate::MAX_WORDS, None)
                .unwrap()
                .words
                .len() as u64;
        assert!(crate::build_direction(&vertices, &triangles, &g, &m, &mut Scratch::default(), words, None).is_ok());
        match crate::build_direction(&vertices, &triangles, &g, &m, &mut Scratch::default(), words - 1, None) {
            Err(crate::DirectionError::TooLarge(e)) => assert!(e.limit == words - 1 && e.count > e.limit, "{e:?}"),
            Err(e) => panic!("{e:?}"),
            Ok(_) => panic!("{words} words made under a limit of {}", words - 1),
        }
    }

    #[test]
    fn a_sliver_counts_the_tiles_along_its_length() {
        // A triangle 3.5 units long and 10⁻⁶ wide, facing the direction: its area covers no tile,
        // but it crosses 3.5 / (4 / 256) = 224 tile widths along x on 256² tiles.
        let vertices = [[-1.75, 0.0, 0.0], [1.75, 0.0, 0.0], [1.75, 1e-6, 0.0]];
        let triangles = [[0, 1, 2]];
        let areas = Areas::new(&vertices, &triangles);
        let g = grid(256);
        let m = frame([0.0, 0.0, 1.0]);
        let bound = areas.entries_at_least(&g, &m);
        assert_eq!(bound, (224.0 / std::f64::consts::SQRT_2) as u64 + 1);
        assert!(bound <= rasterised(&vertices, &triangles, &g, [0.0, 0.0, 1.0]));
    }
}
