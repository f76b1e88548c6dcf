//! Bakes are reproducible to the byte: thread count does not change the output, and a golden
//! field's content hash is pinned so any change to the bytes is deliberate; the automatic
//! parameters of a few scenes are pinned with the baker revision that chose them.
//!
//! Regenerate the golden values with `UPDATE_EXPECT=1 cargo test -p vlf-tests --test determinism`.

#![forbid(unsafe_code)]

use std::path::Path;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress, Scene, generate, import};
use vlf_runtime::{Field, hex};
use vlf_tests::fixtures;

fn bake_with_threads(scene: &Scene, config: &BakeConfig, threads: usize, path: &Path) -> Vec<u8> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| vlf_bake::bake_scene(scene, config, path, &NoProgress)).expect("bake");
    std::fs::read(path).unwrap()
}

#[test]
fn one_and_two_threads_give_identical_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let tris = generate::random_cube(3000, 0.05, 7);
    let scene = Scene::from_triangles("random", &tris).unwrap();
    // Automatic parameters too: the estimate must be deterministic as well.
    for config in [
        BakeConfig { directions: Some(129), tiles: Some(32), ..BakeConfig::default() },
        BakeConfig { max_bytes: 8 << 20, ..BakeConfig::default() },
    ] {
        let one = bake_with_threads(&scene, &config, 1, &dir.path().join("one.vlf"));
        let two = bake_with_threads(&scene, &config, 2, &dir.path().join("two.vlf"));
        let three = bake_with_threads(&scene, &config, 3, &dir.path().join("three.vlf"));
        assert!(one == two && two == three, "thread count changed the bytes");
    }
}

/// Compares `actual` with the checked-in `fixtures/expected/<name>`, or rewrites it when
/// UPDATE_EXPECT=1.
fn expect(name: &str, actual: &str) {
    expect_or(name, actual, |_| {
        "if deliberate, rerun with UPDATE_EXPECT=1 (and bump the format or baker revision if bytes changed)".into()
    });
}

/// [`expect`], saying `advice(expected)` when the two differ.
fn expect_or(name: &str, actual: &str, advice: impl FnOnce(&str) -> String) {
    let path = fixtures().join("expected").join(name);
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path)
        .unwrap_or_else(|_| panic!("missing {}; run with UPDATE_EXPECT=1 to create it", path.display()));
    assert_eq!(expected, actual, "{name} changed; {}", advice(&expected));
}

#[test]
fn golden_bunny_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bunny.vlf");
    let scene = import::import_paths(&[fixtures().join("meshes/bunny.obj")]).unwrap();
    let config = BakeConfig {
        directions: Some(129),
        tiles: Some(32),
        depth: DepthPolicy { leaf_size: 4, max_depth: 8 },
        ..BakeConfig::default()
    };
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).unwrap();
    let field = Field::open(&path).unwrap();
    let info = vlf_bake::inspect::describe(field.reader());
    expect("bunny-129x32.content-hash", &format!("{}\n", hex(&field.content_hash())));
    expect("bunny-129x32.dump.json", &(serde_json::to_string_pretty(&info).unwrap() + "\n"));
}

/// A field with every section of format 1.1: the glTF room's materials, camera and lights.
#[test]
fn golden_cornell_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cornell.vlf");
    let scene = import::import_paths(&[fixtures().join("meshes/cornell/cornell.gltf")]).unwrap();
    let config = BakeConfig {
        directions: Some(33),
        tiles: Some(16),
        depth: DepthPolicy { leaf_size: 4, max_depth: 8 },
        ..BakeConfig::default()
    };
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).unwrap();
    let field = Field::open(&path).unwrap();
    let info = vlf_bake::inspect::describe(field.reader());
    assert_eq!((info.materials, info.cameras, info.lights), (7, 1, 2));
    expect("cornell-33x16.content-hash", &format!("{}\n", hex(&field.content_hash())));
    expect("cornell-33x16.dump.json", &(serde_json::to_string_pretty(&info).unwrap() + "\n"));
}

/// The automatic parameters of a few scenes, pinned with the baker revision that chose them. The
/// bake cache keys a field by its inputs and request, not by the parameters chosen from them
/// (`crates/vlf-bake/src/cache.rs`), so a change to the choice that keeps `BAKER_REVISION` would
/// let a cache serve a field the new baker would not write. The goldens above use explicit
/// parameters and cannot see it; this one fails, and says to bump the revision.
#[test]
fn automatic_parameters_change_only_with_the_baker_revision() {
    let bunny = import::import_paths(&[fixtures().join("meshes/bunny.obj")]).unwrap();
    let random = |n: usize, size: f64| Scene::from_triangles("random", &generate::random_cube(n, size, 1)).unwrap();
    // 40,000 small triangles in a ball a tenth of the scene's size, and one triangle at each end
    // of a diagonal: few tiles, each crossed by about a thousand triangles (the dense tiles of a
    // scan), which the choice refines.
    let mut tris = generate::random_cube(40_000, 0.004, 1);
    for t in &mut tris {
        *t = t.map(|v| v.map(|c| c * 0.1));
    }
    tris.push([[1.0, 1.0, 1.0], [0.99, 1.0, 1.0], [1.0, 0.99, 1.0]]);
    tris.push([[-1.0, -1.0, -1.0], [-0.99, -1.0, -1.0], [-1.0, -0.99, -1.0]]);
    let cluster = Scene::from_triangles("cluster", &tris).unwrap();
    let scenes = [
        ("bunny", bunny),
        ("random 3000, half-extent 0.05", random(3000, 0.05)),
        ("random 20000, half-extent 0.05", random(20_000, 0.05)),
        ("random 20000, half-extent 0.004", random(20_000, 0.004)),
        ("a dense cluster far inside its bounding sphere", cluster),
    ];
    let mut actual = format!("baker revision {}\n", vlf_bake::BAKER_REVISION);
    for (name, scene) in &scenes {
        let choice = vlf_bake::choose(&vlf_bake::Prepared::new(scene), &BakeConfig::default()).unwrap();
        let p = choice.params;
        let directions = vlf_geom::Lattice::new(p.lattice_n).direction_count();
        actual += &format!(
            "{name}: {directions} directions × {}² tiles, leaf size {}, depth {}\n",
            p.tiles, p.depth.leaf_size, p.depth.max_depth
        );
    }
    expect_or("automatic-parameters.txt", &actual, |expected| {
        if expected.lines().next() == actual.lines().next() {
            "the automatic parameters changed but BAKER_REVISION did not: bump it in \
             crates/vlf-bake/src/sections.rs (and say why in formats/vlf.md §3.2), then rerun with UPDATE_EXPECT=1"
        } else {
            "the automatic parameters changed with BAKER_REVISION: rerun with UPDATE_EXPECT=1"
        }
        .into()
    });
}
