//! Scene files (`formats/scene.md`) loaded against real fields and meshes: what a good file
//! builds, and that each fault a file can have is one error naming the instance and the key.

#![forbid(unsafe_code)]

use std::path::Path;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress};
use vlf_geom::Ray;
use vlf_scene::{SceneFile, SceneFileError};

/// Reads a mesh as the command line does: `vlf-bake`'s importer, world coordinates.
fn meshes(path: &Path) -> Result<Vec<[[f64; 3]; 3]>, String> {
    vlf_bake::import::import_paths(&[path]).map(|s| s.world_vertices()).map_err(|e| e.to_string())
}

/// A directory holding `room.vlf` (the Cornell room, objects `floor`, `lamp`, …), `cube.obj`
/// (a small cube around the origin) and `far.obj` (a triangle far away).
fn setup() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let room = vlf_bake::import::import_paths(&[vlf_tests::fixtures().join("meshes/cornell/cornell.obj")]).unwrap();
    let config = BakeConfig {
        directions: Some(19),
        tiles: Some(8),
        depth: DepthPolicy { leaf_size: 4, max_depth: 4 },
        ..BakeConfig::default()
    };
    vlf_bake::bake_scene(&room, &config, &dir.path().join("room.vlf"), &NoProgress).unwrap();
    let mut cube = Vec::new();
    vlf_bake::generate::write_obj(&mut cube, "cube", &vlf_bake::generate::closed_box([-0.1; 3], [0.1; 3])).unwrap();
    std::fs::write(dir.path().join("cube.obj"), cube).unwrap();
    std::fs::write(dir.path().join("far.obj"), "v 1000 0 0\nv 1001 0 0\nv 1000 1 0\nf 1 2 3\n").unwrap();
    dir
}

fn load(dir: &Path, json: &str) -> Result<vlf_scene::Scene, SceneFileError> {
    let path = dir.join("scene.json");
    std::fs::write(&path, json).unwrap();
    SceneFile::read(&path)?.load(&meshes)
}

#[test]
fn a_file_places_shares_and_edits_fields() {
    let dir = setup();
    let scene = load(
        dir.path(),
        r#"{"instances": [
            {"field": "room.vlf"},
            {"field": "room.vlf", "transform": [1,0,0,100, 0,1,0,0, 0,0,1,0, 0,0,0,1], "mask": 2},
            {"field": "./room.vlf", "transform": [-1,0,0,-100, 0,1,0,0, 0,0,1,0, 0,0,0,1],
             "remove": ["lamp", "floor"],
             "insert": [{"mesh": "cube.obj"}, {"mesh": "cube.obj", "transform": [2,0,0,0, 0,2,0,0.5, 0,0,2,0, 0,0,0,1]}]}
        ]}"#,
    )
    .unwrap();
    assert_eq!(scene.instance_count(), 3);
    // The first two share one unedited field; the third has its own edits.
    assert_eq!(scene.fields().len(), 2);
    let (plain, edited) = (&scene.fields()[0], &scene.fields()[1]);
    assert!(!plain.is_edited());
    // `./room.vlf` is the same file: one mapping.
    assert!(std::sync::Arc::ptr_eq(plain.field(), edited.field()));
    assert_eq!(edited.inserted_count(), 24);
    let removed =
        edited.ids_of(vlf_scene::Object::Name("lamp")).len() + edited.ids_of(vlf_scene::Object::Name("floor")).len();
    assert!(removed > 0);
    assert_eq!(edited.live_count(), (plain.id_count() as usize - removed + 24) as u64);
    assert_eq!(scene.instance(1).unwrap().mask, 2);
    // The inserted cube (at the field's origin, on the floor the third instance removed) is
    // numbered after the field's own triangles, and hit in world units: through the open front
    // of the third instance (x mirrored and moved to -100) along -z at floor height.
    let ray = Ray::new([-100.0, 0.02, 100.0], [0.0, 0.0, -1.0]);
    let hit = scene.closest_hit(&ray, 1).unwrap();
    assert_eq!(hit.instance, 2);
    assert!(hit.hit.prim >= plain.id_count(), "{hit:?}");
    assert!((hit.hit.t - 99.9).abs() < 1e-4, "{hit:?}");
    // The plain instance keeps its floor there.
    let down = Ray::new([0.0, 5.0, 0.0], [0.0, -1.0, 0.0]);
    assert!((scene.closest_hit(&down, 1).unwrap().hit.t - 5.0).abs() < 1e-5);
    let down = Ray::new([-100.0, 5.0, 5.0], [0.0, -1.0, 0.0]);
    assert!(scene.closest_hit(&down, 1).is_none_or(|h| h.hit.t > 5.0 + 1e-3 || h.hit.prim >= plain.id_count()));
}

#[test]
fn every_fault_names_the_instance_and_the_key() {
    let dir = setup();
    let cases: &[(&str, &[&str])] = &[
        (
            r#"{"instances": [{"field": "room.vlf"}, {"field": "nowhere.vlf"}]}"#,
            &["instance 1", "key \"field\"", "nowhere.vlf"],
        ),
        (r#"{"instances": [{"field": "cube.obj"}]}"#, &["instance 0", "key \"field\""]),
        (
            r#"{"instances": [{"field": "room.vlf", "remove": ["floor", "sofa"]}]}"#,
            &["instance 0", "key \"remove\"", "\"sofa\"", "\"floor\""],
        ),
        (
            r#"{"instances": [{"field": "room.vlf", "insert": [{"mesh": "none.obj"}]}]}"#,
            &["instance 0", "key \"insert\"", "none.obj"],
        ),
        (
            r#"{"instances": [{"field": "room.vlf", "insert": [{"mesh": "cube.obj"}, {"mesh": "far.obj"}]}]}"#,
            &["key \"insert\"", "[1]", "bounding sphere"],
        ),
        (
            r#"{"instances": [{"field": "room.vlf"}, {"field": "room.vlf", "transform": [1,0,0,0, 2,0,0,0, 0,0,1,0, 0,0,0,1]}]}"#,
            &["instance 1", "key \"transform\"", "singular"],
        ),
        (
            r#"{"instances": [{"field": "room.vlf", "colour": "red"}]}"#,
            &["instance 0", "key \"colour\"", "unknown key"],
        ),
    ];
    for (json, want) in cases {
        let e = load(dir.path(), json).err().unwrap_or_else(|| panic!("{json} loaded")).to_string();
        assert!(e.contains("scene.json"), "{e}");
        for w in *want {
            assert!(e.contains(w), "{json}: {e:?} lacks {w:?}");
        }
    }
    let e = SceneFile::read(&dir.path().join("absent.json")).unwrap_err().to_string();
    assert!(e.contains("cannot read scene file") && e.contains("absent.json"), "{e}");
}
