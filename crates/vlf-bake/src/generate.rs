//! Seeded, deterministic scene generators: the paper's uniformly distributed random triangles
//! (§6.2, Figure 5) and the adversarial families the oracle tests use. Each can be written as OBJ
//! so the command line can bake it.

use std::io::{self, Write};

/// A small, fast, seedable generator (SplitMix64), so scenes are identical on every platform.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

pub type Tri = [[f32; 3]; 3];

/// The default edge scale of [`random_cube`]: each vertex lies within ±0.05 of the triangle's
/// centre, in a cube of side 2. Fixed, as in the paper, so that a scene of more triangles is
/// denser (its depth complexity grows with the count, which is what stresses an acceleration
/// structure). Measured: of 20,000 random lines through the cube, 74% hit one of 9K triangles
/// (the paper's Figure 5 outside view, a cloud one can partly see through) and 88% one of 16K.
pub const DEFAULT_TRIANGLE_SIZE: f64 = 0.05;

/// `count` triangles with centres uniform in `[-1, 1]³` and vertices uniform within `±size` of
/// the centre.
pub fn random_cube(count: usize, size: f64, seed: u64) -> Vec<Tri> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            let c = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
            std::array::from_fn(|_| std::array::from_fn(|k| (c[k] + rng.range(-size, size)) as f32))
        })
        .collect()
}

/// An axis-aligned grid of `cells × cells` unit quads, each split into two triangles along a
/// diagonal, in each of `layers` parallel planes (z = 0, 1, …), all coordinates exact integers
/// scaled by `scale`: shared edges and vertices everywhere, and rays along grid lines.
pub fn grid(cells: u32, layers: u32, scale: f32) -> Vec<Tri> {
    let mut out = Vec::new();
    for z in 0..layers {
        for y in 0..cells {
            for x in 0..cells {
                let p = |dx: u32, dy: u32| [(x + dx) as f32 * scale, (y + dy) as f32 * scale, z as f32 * scale];
                let (a, b, c, d) = (p(0, 0), p(1, 0), p(1, 1), p(0, 1));
                if (x + y) % 2 == 0 {
                    out.push([a, b, c]);
                    out.push([a, c, d]);
                } else {
                    out.push([a, b, d]);
                    out.push([b, c, d]);
                }
            }
        }
    }
    out
}

/// A closed axis-aligned box mesh (12 triangles) from `lo` to `hi`.
pub fn closed_box(lo: [f32; 3], hi: [f32; 3]) -> Vec<Tri> {
    let v = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    faces.iter().flat_map(|f| [[v(f[0]), v(f[1]), v(f[2])], [v(f[0]), v(f[2]), v(f[3])]]).collect()
}

/// Long thin slivers: `count` triangles of length up to 2 and width down to 1e-4, random
/// orientation, in `[-1, 1]³`.
pub fn slivers(count: usize, seed: u64) -> Vec<Tri> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            let a = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
            let b = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
            let width = 10f64.powf(rng.range(-4.0, -2.0));
            let off = [rng.range(-width, width), rng.range(-width, width), rng.range(-width, width)];
            let t = rng.unit();
            let c = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]) + off[k]);
            [a.map(|v| v as f32), b.map(|v| v as f32), c.map(|v: f64| v as f32)]
        })
        .collect()
}

/// Random triangles mixed with exactly degenerate ones (repeated vertices, collinear vertices),
/// which the importer drops: `count` of each kind.
pub fn with_degenerates(count: usize, seed: u64) -> Vec<Tri> {
    let mut rng = Rng::new(seed);
    let mut out = random_cube(count, 0.2, seed);
    for i in 0..count {
        let p = [rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32];
        let q = [p[0] + 0.25, p[1], p[2]];
        let mid = [p[0] + 0.125, p[1], p[2]];
        out.push(if i % 2 == 0 { [p, p, q] } else { [p, mid, q] });
    }
    out
}

/// Writes triangles as a plain OBJ (`v` and `f` lines, one object named `name`). Coordinates are
/// printed in their shortest exact form, so reading the OBJ back gives the same f32 bits.
pub fn write_obj(w: &mut impl Write, name: &str, triangles: &[Tri]) -> io::Result<()> {
    writeln!(w, "# {} triangles, generated by vlf-bake", triangles.len())?;
    writeln!(w, "o {name}")?;
    for t in triangles {
        for v in t {
            writeln!(w, "v {:?} {:?} {:?}", v[0], v[1], v[2])?;
        }
    }
    for i in 0..triangles.len() {
        writeln!(w, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3)?;
    }
    Ok(())
}
