//! Issue 11, items 1 to 3, through the binary at its default parameters: the smallest meshes bake,
//! duplicated triangles keep the field small and are reported, and a scene far from the origin
//! keeps every triangle and answers rays.

#![forbid(unsafe_code)]

mod common;

use common::{mesh, s, tempdir, vlf};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use vlf_runtime::Field;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A small deterministic generator, so the meshes are the same on every run.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn in_range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

#[test]
fn the_smallest_meshes_bake_with_the_defaults() {
    let dir = tempdir();
    let one = write(dir.path(), "one.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let plane = write(dir.path(), "plane.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
    for (input, triangles) in
        [(one, "1 triangle,"), (plane, "2 triangles,"), (mesh("small/hierarchy.gltf"), "2 triangles,")]
    {
        let out = dir.path().join("out.vlf");
        let r = vlf(&["bake", s(&input), "-o", s(&out)]).ok();
        assert!(r.stdout.contains(triangles), "{}: {}", r.what, r.stdout);
        assert!(r.stderr.contains("chose 9 directions × 16² tiles"), "{}: {}", r.what, r.stderr);
        let field = Field::open(&out).unwrap();
        assert!(std::fs::metadata(&out).unwrap().len() < 64 << 10, "a tiny mesh's field stays tiny");
        drop(field);
        let dump = vlf(&["dump", s(&out)]).ok();
        if triangles.starts_with("1 ") {
            assert!(dump.stdout.contains("(1 triangle, blake3"), "{}", dump.stdout);
            assert!(dump.stdout.contains("0 materials, 0 cameras, 0 lights (1 source)"), "{}", dump.stdout);
        }
        std::fs::remove_file(&out).unwrap();
    }
}

#[test]
fn duplicated_triangles_are_merged_and_named_and_the_field_stays_small() {
    // The mesh: 5,001 triangles of which only 2 are distinct.
    let dir = tempdir();
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n");
    for i in 0..5001 {
        text.push_str(if i % 2 == 0 { "f 1 2 3\n" } else { "f 1 2 4\n" });
    }
    let input = write(dir.path(), "dups.obj", &text);
    let out = dir.path().join("dups.vlf");
    let r = vlf(&["bake", s(&input), "-o", s(&out)]).ok();
    assert!(r.stdout.contains(": 2 triangles,"), "{}", r.stdout);
    assert!(
        r.stderr.contains(
            "warning: 4999 triangles have the same three vertices as an earlier triangle and were merged into it"
        ),
        "{}",
        r.stderr
    );
    let bytes = std::fs::metadata(&out).unwrap().len();
    assert!(bytes < 1 << 20, "the field of two distinct triangles is {bytes} bytes");
    let field = Field::open(&out).unwrap();
    assert_eq!(field.triangle_count(), 2);
}

#[test]
fn a_scene_far_from_the_origin_keeps_every_triangle() {
    // The mesh: 2,000 triangles about 0.1 across, centred at 1e7.
    let dir = tempdir();
    let mut rng = Lcg(7);
    let mut text = String::new();
    for i in 0..2000 {
        let c: Vec<f64> = (0..3).map(|_| 1e7 + rng.in_range(-1.0, 1.0)).collect();
        for _ in 0..3 {
            let v: Vec<f64> = c.iter().map(|&x| x + rng.in_range(-0.05, 0.05)).collect();
            writeln!(text, "v {:.9} {:.9} {:.9}", v[0], v[1], v[2]).unwrap();
        }
        writeln!(text, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3).unwrap();
    }
    let input = write(dir.path(), "far.obj", &text);
    let out = dir.path().join("far.vlf");
    let r = vlf(&["bake", s(&input), "-o", s(&out)]).ok();
    assert!(r.stdout.contains(": 2000 triangles,"), "{}", r.stdout);
    assert!(!r.stderr.contains("dropped"), "{}", r.stderr);
    // Primary rays from the default outside view see the scene.
    let rays = dir.path().join("rays.bin");
    let hits = dir.path().join("hits.bin");
    vlf(&["rays", s(&out), "-o", s(&rays), "--width", "64", "--height", "64", "-q"]).ok();
    let t = vlf(&["trace", s(&out), "--rays", s(&rays), "-o", s(&hits), "--json"]).ok().json();
    let hit = t["hits"].as_u64().unwrap();
    // 318 of 4096 hit at the origin too: the scene covers about 8% of the view.
    assert!(hit > 250, "{hit} of 4096 rays hit a scene 1e7 from the origin");
}
