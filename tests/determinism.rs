//! Bakes are reproducible to the byte: thread count does not change the output, and a golden
//! field's content hash is pinned so any change to the bytes is deliberate.
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
    let path = fixtures().join("expected").join(name);
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path)
        .unwrap_or_else(|_| panic!("missing {}; run with UPDATE_EXPECT=1 to create it", path.display()));
    assert_eq!(
        expected, actual,
        "{name} changed; if deliberate, rerun with UPDATE_EXPECT=1 (and bump the format or baker revision if bytes changed)"
    );
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
