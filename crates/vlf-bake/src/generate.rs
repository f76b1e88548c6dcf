//! Seeded, deterministic scene generators: the paper's uniformly distributed random triangles
//! (§6.2, Figure 5) and the adversarial families the oracle tests use. Each can be written as OBJ
//! so the command line can bake it; the `_iter` forms produce triangles one at a time, so a scene
//! of any size streams to its file in constant memory ([`write_obj_iter`]), and
//! [`obj_bytes_at_most`] tells how large that file can be before it is written.

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
    random_cube_iter(count as u64, size, seed).collect()
}

/// The triangles of [`random_cube`], one at a time.
pub fn random_cube_iter(count: u64, size: f64, seed: u64) -> impl Iterator<Item = Tri> {
    let mut rng = Rng::new(seed);
    (0..count).map(move |_| {
        let c = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        std::array::from_fn(|_| std::array::from_fn(|k| (c[k] + rng.range(-size, size)) as f32))
    })
}

/// An axis-aligned grid of `cells × cells` unit quads, each split into two triangles along a
/// diagonal, in each of `layers` parallel planes (z = 0, 1, …), all coordinates exact integers
/// scaled by `scale`: shared edges and vertices everywhere, and rays along grid lines.
pub fn grid(cells: u32, layers: u32, scale: f32) -> Vec<Tri> {
    grid_iter(cells, layers, scale).collect()
}

/// The triangles of [`grid`], one at a time: `2 · cells² · layers` of them.
pub fn grid_iter(cells: u32, layers: u32, scale: f32) -> impl Iterator<Item = Tri> {
    (0..layers).flat_map(move |z| {
        (0..cells).flat_map(move |y| {
            (0..cells).flat_map(move |x| {
                let p = |dx: u32, dy: u32| [(x + dx) as f32 * scale, (y + dy) as f32 * scale, z as f32 * scale];
                let (a, b, c, d) = (p(0, 0), p(1, 0), p(1, 1), p(0, 1));
                if (x + y) % 2 == 0 { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] }
            })
        })
    })
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
    slivers_iter(count as u64, seed).collect()
}

/// The triangles of [`slivers`], one at a time. Every coordinate is within ±1.01.
pub fn slivers_iter(count: u64, seed: u64) -> impl Iterator<Item = Tri> {
    let mut rng = Rng::new(seed);
    (0..count).map(move |_| {
        let a = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let b = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let width = 10f64.powf(rng.range(-4.0, -2.0));
        let off = [rng.range(-width, width), rng.range(-width, width), rng.range(-width, width)];
        let t = rng.unit();
        let c = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]) + off[k]);
        [a.map(|v| v as f32), b.map(|v| v as f32), c.map(|v: f64| v as f32)]
    })
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
    write_obj_iter(w, name, triangles.len() as u64, triangles.iter().copied())
}

/// [`write_obj`] of the `count` triangles `triangles` yields, streamed: the vertices as they come,
/// then the faces, which need nothing but the count. Fails if the iterator yields another number
/// of triangles.
pub fn write_obj_iter(
    w: &mut impl Write,
    name: &str,
    count: u64,
    triangles: impl Iterator<Item = Tri>,
) -> io::Result<()> {
    writeln!(w, "# {count} triangles, generated by vlf-bake")?;
    writeln!(w, "o {name}")?;
    let mut written = 0u64;
    for t in triangles {
        for v in t {
            writeln!(w, "v {:?} {:?} {:?}", v[0], v[1], v[2])?;
        }
        written += 1;
    }
    if written != count {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{written} triangles, not the {count} announced"),
        ));
    }
    for i in 0..count {
        writeln!(w, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3)?;
    }
    Ok(())
}

/// The most characters `{:?}` prints for a finite f32 of magnitude at most `max_abs`. It prints
/// nine significant digits at most: below 10⁻⁴ and from 10¹⁶ on in exponent form, fifteen
/// characters at most (`-1.12943956e-13`); from 10⁻⁴ to 10⁹ as a decimal, fifteen at most too
/// (a sign, `0.000` and nine digits); from 10⁹ to 10¹⁶ as a decimal of up to sixteen digits and `.0`.
fn f32_debug_len_at_most(max_abs: f64) -> u64 {
    if max_abs < 1e9 { 15 } else { 19 }
}

/// The exact number of decimal digits in `1, 2, …, n`.
fn digits_up_to(n: u64) -> u64 {
    let (mut total, mut start, mut digits) = (0u64, 1u64, 1u64);
    while start <= n {
        let end = start.checked_mul(10).map_or(n, |next| (next - 1).min(n));
        total = total.saturating_add((end - start + 1).saturating_mul(digits));
        if end == n {
            break;
        }
        start = end + 1;
        digits += 1;
    }
    total
}

/// An upper bound on the bytes [`write_obj_iter`] writes for `count` triangles named `name` whose
/// coordinates are within `±max_abs`: exact for the header and the faces, and every coordinate
/// counted at its longest. Saturates instead of overflowing.
pub fn obj_bytes_at_most(name: &str, count: u64, max_abs: f64) -> u64 {
    let header = format!("# {count} triangles, generated by vlf-bake\no {name}\n").len() as u64;
    let vertex_line = 2 + 3 * f32_debug_len_at_most(max_abs) + 3; // "v x y z\n"
    let vertices = count.saturating_mul(3).saturating_mul(vertex_line);
    // "f a b c\n": four more bytes per face than the digits of its three indices, 1..=3·count.
    let faces = count.saturating_mul(5).saturating_add(digits_up_to(count.saturating_mul(3)));
    header.saturating_add(vertices).saturating_add(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj_len(name: &str, tris: &[Tri]) -> u64 {
        let mut bytes = Vec::new();
        write_obj(&mut bytes, name, tris).unwrap();
        bytes.len() as u64
    }

    #[test]
    fn the_streamed_scenes_are_the_collected_ones() {
        assert_eq!(random_cube_iter(50, 0.1, 3).collect::<Vec<_>>(), random_cube(50, 0.1, 3));
        assert_eq!(grid_iter(5, 2, 1.0).count(), 2 * 5 * 5 * 2);
        assert_eq!(slivers_iter(40, 9).collect::<Vec<_>>(), slivers(40, 9));
        let tris = random_cube(7, 0.05, 1);
        let mut short = Vec::new();
        assert!(write_obj_iter(&mut short, "x", 8, tris.iter().copied()).is_err(), "a count that lies");
    }

    #[test]
    fn obj_sizes_are_bounded_and_faces_counted_exactly() {
        assert_eq!(digits_up_to(0), 0);
        assert_eq!(digits_up_to(9), 9);
        assert_eq!(digits_up_to(10), 11);
        assert_eq!(digits_up_to(1000), 9 + 180 + 2700 + 4);
        for (name, tris, max_abs, loose) in [
            ("random", random_cube(3000, 0.05, 2), 1.05, 1.5),
            ("random", random_cube(500, 1e-6, 5), 1.0, 1.5),
            ("slivers", slivers(3000, 4), 1.01, 1.5),
            ("grid", grid(40, 4, 1.0), 40.0, 3.0),
            ("grid", grid(3, 4, 3e8), 9e8, 3.0),
        ] {
            let actual = obj_len(name, &tris);
            let bound = obj_bytes_at_most(name, tris.len() as u64, max_abs);
            assert!(actual <= bound, "{name}: {actual} > {bound}");
            assert!((bound as f64) < actual as f64 * loose, "{name}: {bound} is a loose bound for {actual}");
        }
        // Faces are counted exactly: triangles whose coordinates all print as `0.0`.
        let zeros = vec![[[0.0f32; 3]; 3]; 1234];
        let header = "# 1234 triangles, generated by vlf-bake\no z\n".len() as u64;
        let face_bytes = obj_len("z", &zeros) - header - 1234 * 3 * "v 0.0 0.0 0.0\n".len() as u64;
        let bound_faces = obj_bytes_at_most("z", 1234, 1.0) - header - 1234 * 3 * 50;
        assert_eq!(face_bytes, bound_faces);
        assert_eq!(obj_bytes_at_most("x", u64::MAX, 1.0), u64::MAX, "saturates");
    }

    #[test]
    fn f32_debug_lengths_stay_within_the_bound() {
        let mut rng = Rng::new(11);
        let mut longest = [0u64; 2];
        for i in 0..1_000_000 {
            let bits = rng.next_u64() as u32;
            let x = f32::from_bits(bits);
            if !x.is_finite() {
                continue;
            }
            let len = format!("{x:?}").len() as u64;
            let small = (x.abs() as f64) < 1e9;
            assert!(len <= f32_debug_len_at_most(x.abs() as f64), "{x:?} ({i})");
            longest[small as usize] = longest[small as usize].max(len);
        }
        // The longest forms: a nine-digit exponent form, and a decimal of sixteen digits.
        for (text, len) in [("-1.12943956e-13", 15), ("-2593676000000000.0", 19), ("-123456790.0", 12)] {
            let x: f32 = text.parse().unwrap();
            assert_eq!((format!("{x:?}"), format!("{x:?}").len() as u64), (text.to_owned(), len));
            assert!(len <= f32_debug_len_at_most(x.abs() as f64), "{x:?}");
        }
        assert!(longest[0] >= 18 && longest[1] >= 14, "the bounds are nearly reached: {longest:?}");
    }
}
