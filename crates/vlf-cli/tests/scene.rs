//! `trace --scene` and `render --scene` (issue 13): instances of baked fields from a scene file
//! (`formats/scene.md`), hits naming the instance, animated pictures, and the command line's
//! conventions for their faults.

#![forbid(unsafe_code)]

mod common;

use common::{SMALL, names_in, s, tempdir, vlf};
use std::path::{Path, PathBuf};

/// A closed box from -1 to 1 (12 triangles) baked as `cube.vlf` in `dir`.
fn cube(dir: &Path) -> PathBuf {
    let obj = dir.join("cube.obj");
    let mut file = std::fs::File::create(&obj).unwrap();
    vlf_bake::generate::write_obj(&mut file, "cube", &vlf_bake::generate::closed_box([-1.0; 3], [1.0; 3])).unwrap();
    let field = dir.join("cube.vlf");
    vlf(&[&["bake", s(&obj), "-o", s(&field), "-q"][..], &SMALL].concat()).ok();
    field
}

/// Rays as `formats/rays.md` records.
fn write_rays(path: &Path, rays: &[([f32; 3], [f32; 3])]) {
    let mut bytes = Vec::new();
    for (o, d) in rays {
        for v in [o[0], o[1], o[2], 0.0, d[0], d[1], d[2], f32::INFINITY] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// `(t, prim)` of each 16-byte hit record.
fn read_hits(path: &Path) -> Vec<(f32, u32)> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(16)
        .map(|h| (f32::from_le_bytes(h[0..4].try_into().unwrap()), u32::from_le_bytes(h[4..8].try_into().unwrap())))
        .collect()
}

/// Two cubes: instance 0 at x = 10, instance 1 mirrored in x, stretched to half-width 3 along x,
/// at x = -10.
const SCENE: &str = r#"{"instances": [
    {"field": "cube.vlf", "transform": [1,0,0,10, 0,1,0,0, 0,0,1,0, 0,0,0,1]},
    {"field": "cube.vlf", "transform": [-3,0,0,-10, 0,1,0,0, 0,0,1,0, 0,0,0,1], "mask": 2}
]}"#;

#[test]
fn trace_scene_names_the_instance_and_measures_t_in_world_units() {
    let dir = tempdir();
    cube(dir.path());
    let scene = dir.path().join("scene.json");
    std::fs::write(&scene, SCENE).unwrap();
    let (rays, hits, ids) = (dir.path().join("r.bin"), dir.path().join("h.bin"), dir.path().join("i.bin"));
    write_rays(
        &rays,
        &[
            ([0.0, 0.1, 0.2], [1.0, 0.0, 0.0]),  // +x: the first cube's face at x = 9
            ([0.0, 0.1, 0.2], [-2.0, 0.0, 0.0]), // -x, direction of length 2: face at x = -7, t = 3.5
            ([0.0, 5.0, 0.0], [1.0, 0.0, 0.0]),  // above both
        ],
    );
    let args = ["trace", "--scene", s(&scene), "--rays", s(&rays), "-o", s(&hits), "--instance-ids", s(&ids)];
    let j = vlf(&[&args[..], &["--json"]].concat()).ok().json();
    assert_eq!((j["rays"].as_u64(), j["hits"].as_u64(), j["invalid"].as_u64()), (Some(3), Some(2), Some(0)), "{j}");
    let h = read_hits(&hits);
    assert!((h[0].0 - 9.0).abs() < 1e-5 && h[0].1 < 12, "{h:?}");
    assert!((h[1].0 - 3.5).abs() < 1e-5 && h[1].1 < 12, "{h:?}");
    assert_eq!((h[2].0, h[2].1), (f32::INFINITY, u32::MAX));
    let ids: Vec<u32> =
        std::fs::read(&ids).unwrap().chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().unwrap())).collect();
    assert_eq!(ids, [0, 1, u32::MAX]);
    // Any hit: the same hits and misses.
    let any = dir.path().join("any.bin");
    vlf(&["trace", "--scene", s(&scene), "--rays", s(&rays), "-o", s(&any), "--any-hit", "-q"]).ok();
    assert_eq!(read_hits(&any).iter().map(|h| h.1 != u32::MAX).collect::<Vec<_>>(), [true, true, false]);
    // The same field traced alone, the ray moved into its space by hand: the same triangle.
    let alone = dir.path().join("alone.bin");
    write_rays(&rays, &[([-10.0, 0.1, 0.2], [1.0, 0.0, 0.0])]);
    vlf(&["trace", s(&dir.path().join("cube.vlf")), "--rays", s(&rays), "-o", s(&alone), "-q"]).ok();
    assert_eq!(read_hits(&alone)[0].1, h[0].1);
}

#[test]
fn scene_faults_are_one_error_naming_the_instance_and_the_key() {
    let dir = tempdir();
    cube(dir.path());
    let (rays, hits) = (dir.path().join("r.bin"), dir.path().join("h.bin"));
    write_rays(&rays, &[([0.0; 3], [1.0, 0.0, 0.0])]);
    let scene = dir.path().join("bad.json");
    for (json, phrases) in [
        (
            r#"{"instances": [{"field": "cube.vlf"}, {"field": "gone.vlf"}]}"#,
            &["instance 1", "key \"field\"", "gone.vlf"][..],
        ),
        (
            r#"{"instances": [{"field": "cube.vlf", "remove": ["lid"]}]}"#,
            &["instance 0", "key \"remove\"", "\"lid\"", "\"cube\""],
        ),
        (r#"{"instances": [{"field": "cube.vlf", "scale": 2}]}"#, &["instance 0", "key \"scale\"", "unknown key"]),
        (
            r#"{"instances": [{"field": "cube.vlf", "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 1,0,0,1]}]}"#,
            &["instance 0", "key \"transform\"", "last row"],
        ),
    ] {
        std::fs::write(&scene, json).unwrap();
        vlf(&["trace", "--scene", s(&scene), "--rays", s(&rays), "-o", s(&hits)]).fails_saying(phrases);
        let png = dir.path().join("p.png");
        vlf(&["render", "--scene", s(&scene), "-o", s(&png)]).fails_saying(phrases);
    }
    // A field and a scene, flags that need --scene or --frames: bad command lines.
    let field = dir.path().join("cube.vlf");
    vlf(&["trace", s(&field), "--scene", s(&scene), "--rays", s(&rays), "-o", s(&hits)]).fails_with(2);
    vlf(&["trace", s(&field), "--rays", s(&rays), "-o", s(&hits), "--instance-ids", s(&hits)]).fails_with(2);
    vlf(&["trace", "--rays", s(&rays), "-o", s(&hits)]).fails_with(2);
    vlf(&["render", s(&field), "-o", "p.png", "--frames", "2"]).fails_with(2);
    vlf(&["render", "--scene", s(&scene), "-o", "p.png", "--move", "1"]).fails_with(2);
    vlf(&["render", "--scene", s(&scene), "-o", "p.png", "--frames", "0"]).fails_with(2);
    // --spin and --frame-ms mean nothing without --frames either: refused as --move is, not ignored.
    for extra in [&["--move", "1"][..], &["--spin", "45"], &["--frame-ms", "100"], &["--path", "1,0,0"]] {
        for source in [&["--scene", s(&scene)][..], &[s(&field)]] {
            let r = vlf(&[&["render"][..], source, &["-o", "p.png"], extra].concat()).fails_with(2);
            assert!(
                r.stderr.contains("required arguments were not provided") && r.stderr.contains("--frames <N>"),
                "`{}`: {}",
                r.what,
                r.stderr
            );
        }
    }
    assert_eq!(names_in(dir.path()), ["bad.json", "cube.obj", "cube.vlf", "r.bin"], "something was written");
}

#[test]
fn render_scene_frames_make_an_animated_png() {
    let dir = tempdir();
    cube(dir.path());
    let scene = dir.path().join("scene.json");
    std::fs::write(&scene, SCENE).unwrap();
    let png = dir.path().join("anim.png");
    let args = ["render", "--scene", s(&scene), "--width", "48", "--samples", "1"];
    let moving = ["--frames", "3", "--move", "0", "--path", "0,4,0", "--spin", "45"];
    let j = vlf(&[&args[..], &moving, &["-o", s(&png), "--json"]].concat()).ok().json();
    assert_eq!((j["frames"].as_u64(), j["width"].as_u64(), j["height"].as_u64()), (Some(3), Some(48), Some(36)), "{j}");
    assert_eq!(j["rays"]["primary"].as_u64(), Some(3 * 48 * 36));
    let bytes = std::fs::read(&png).unwrap();
    // acTL: 3 frames, looped forever; the first frame is the default image, the others fdAT.
    let at = bytes.windows(4).position(|w| w == b"acTL").expect("an animated PNG");
    assert_eq!(&bytes[at + 4..at + 12], &[0, 0, 0, 3, 0, 0, 0, 0]);
    assert_eq!(bytes.windows(4).filter(|w| *w == b"fcTL").count(), 3);
    assert!(bytes.windows(4).any(|w| w == b"fdAT"));
    let (w, h, rgb) = vlf_render::decode_png(&bytes).unwrap();
    assert_eq!((w, h, rgb.len()), (48, 36, 48 * 36 * 3));
    // One frame: a plain PNG, and a --move of an instance the scene lacks is refused.
    let one = dir.path().join("one.png");
    vlf(&[&args[..], &["-o", s(&one), "-q"]].concat()).ok();
    assert!(!std::fs::read(&one).unwrap().windows(4).any(|w| w == b"acTL"));
    vlf(&[&args[..], &["-o", s(&one), "--frames", "2", "--move", "5"]].concat())
        .fails_saying(&["--move 5", "instances 0 to 1"]);
}
