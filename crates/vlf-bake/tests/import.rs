//! Integration tests of the OBJ and glTF importers against the meshes in `fixtures/meshes/`.

#![forbid(unsafe_code)]

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use vlf_bake::import::{import_path, import_paths};
use vlf_bake::{ImportError, Scene, SceneBuilder};
use vlf_format::{NO_INDEX, source_kind};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes").join(name)
}

/// The scene of `name`, its triangles put back in import order (the tests below check the
/// importers face by face; `morton_order_is_a_permutation_of_import_order` checks the order).
fn import(name: &str) -> Scene {
    in_import_order(import_paths(&[fixture(name)]).unwrap_or_else(|e| panic!("{name}: {e}")))
}

/// `scene` with its triangles (and their provenance) sorted by source, then index within it:
/// the order the importers produced them in, before the builder put them in Morton order. The
/// kept triangle of every duplicate is renamed to match.
fn in_import_order(mut scene: Scene) -> Scene {
    let mut order: Vec<u32> = (0..scene.len() as u32).collect();
    order.sort_by_key(|&k| (scene.provenance[k as usize].source, scene.provenance[k as usize].index));
    let mut new_id = vec![0u32; order.len()];
    for (k, &old) in order.iter().enumerate() {
        new_id[old as usize] = k as u32;
    }
    scene.triangles = order.iter().map(|&old| scene.triangles[old as usize]).collect();
    scene.provenance = order.iter().map(|&old| scene.provenance[old as usize]).collect();
    for d in &mut scene.duplicates {
        d.triangle = new_id[d.triangle as usize];
    }
    scene.duplicates.sort_by_key(|d| d.triangle);
    scene
}

fn import_err(name: &str) -> ImportError {
    match import_paths(&[fixture(name)]) {
        Ok(scene) => panic!("{name} imported {} triangles, expected an error", scene.len()),
        Err(e) => {
            let file = Path::new(name).file_name().unwrap().to_str().unwrap();
            assert!(e.to_string().contains(file), "the message of {name} does not name the file: {e}");
            e
        }
    }
}

fn string(scene: &Scene, offset: u32, length: u32) -> &str {
    std::str::from_utf8(&scene.strings[offset as usize..(offset + length) as usize]).unwrap()
}

fn input_name(scene: &Scene, i: usize) -> &str {
    string(scene, scene.inputs[i].name_offset, scene.inputs[i].name_length)
}

fn source_name(scene: &Scene, s: usize) -> &str {
    string(scene, scene.sources[s].name_offset, scene.sources[s].name_length)
}

/// Every triangle's vertices in world coordinates, rounded to f32 (the stored vertex plus the
/// scene's centre; exact for the small coordinates of the fixtures).
fn world(scene: &Scene) -> Vec<[[f32; 3]; 3]> {
    scene.world_vertices().iter().map(|t| t.map(|v| v.map(|c| c as f32))).collect()
}

/// The world vertices of the triangles that came from `source`, with their index within it.
fn triangles_of(scene: &Scene, source: u32) -> Vec<(u32, [[f32; 3]; 3])> {
    let vertices = world(scene);
    scene.provenance.iter().zip(vertices).filter(|(p, _)| p.source == source).map(|(p, v)| (p.index, v)).collect()
}

fn bounds(triangles: &[(u32, [[f32; 3]; 3])]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (_, t) in triangles {
        for v in t {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    (lo, hi)
}

fn assert_close(actual: [f32; 3], expected: [f64; 3], tolerance: f64) {
    for k in 0..3 {
        assert!(
            (actual[k] as f64 - expected[k]).abs() <= tolerance,
            "vertex {actual:?} differs from the expected {expected:?}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Reference meshes

#[test]
fn bunny_obj() {
    let scene = import("bunny.obj");
    // 3,674 faces, none of zero area.
    assert_eq!(scene.len(), 3674);
    assert_eq!(scene.report.dropped_degenerate, 0);
    assert_eq!((scene.report.skipped_points, scene.report.skipped_lines), (0, 0));
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);

    assert_eq!(scene.inputs.len(), 1);
    assert_eq!(input_name(&scene, 0), "bunny.obj");
    assert_eq!(scene.inputs[0].triangle_count, 3674);
    let bytes = std::fs::read(fixture("bunny.obj")).unwrap();
    assert_eq!(scene.inputs[0].file_hash, *blake3::hash(&bytes).as_bytes());

    // No `o`/`g` statement: one model, which tobj names "unnamed_object".
    assert_eq!(scene.sources.len(), 1);
    let s = &scene.sources[0];
    assert_eq!(
        (s.input, s.kind, s.mesh, s.primitive, s.node, s.material),
        (0, source_kind::OBJ_OBJECT, 0, 0, NO_INDEX, NO_INDEX)
    );
    assert_eq!(source_name(&scene, 0), "unnamed_object");
    assert!(scene.provenance.iter().enumerate().all(|(i, p)| p.source == 0 && p.index == i as u32));

    // The first triangle is the first face, vertex for vertex.
    let text = String::from_utf8(bytes).unwrap();
    let vertices: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let c: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [c[0], c[1], c[2]]
        })
        .collect();
    let face: Vec<usize> = text
        .lines()
        .find_map(|l| l.strip_prefix("f "))
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    // Parsed in f64 and stored in f32 relative to the centre: within f32 rounding of the text.
    let first = scene.world_vertices()[0];
    for (k, &f) in face.iter().take(3).enumerate() {
        assert_close(first[k].map(|c| c as f32), vertices[f - 1], 1e-6);
    }
}

/// The JSON and binary chunks of a GLB file, read by hand.
fn glb_chunks(bytes: &[u8]) -> (Value, Vec<u8>) {
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..4], b"glTF");
    let json_len = u32_at(12);
    let json: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    (json, bytes[bin_at + 8..bin_at + 8 + bin_len].to_vec())
}

/// Element `i` of a tightly packed accessor, as f64 components.
fn accessor_element(json: &Value, bin: &[u8], accessor: usize, i: usize) -> Vec<f64> {
    let a = &json["accessors"][accessor];
    let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let n = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        t => panic!("{t}"),
    };
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    (0..n)
        .map(|k| {
            let at = start + (i * n + k) * 4;
            let word: [u8; 4] = bin[at..at + 4].try_into().unwrap();
            match a["componentType"].as_u64().unwrap() {
                5125 => u32::from_le_bytes(word) as f64,
                5126 => f32::from_le_bytes(word) as f64,
                c => panic!("{c}"),
            }
        })
        .collect()
}

#[test]
fn bunny_scene_glb() {
    let scene = import("bunny_scene.glb");
    // Two bunnies of 3,674 triangles and a ground quad of 2; none of zero area after transforms.
    assert_eq!(scene.len(), 7350);
    assert_eq!(scene.report.dropped_degenerate, 0);
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);
    assert_eq!(input_name(&scene, 0), "bunny_scene.glb");
    assert_eq!(scene.inputs[0].triangle_count, 7350);

    let described: Vec<_> = (0..scene.sources.len())
        .map(|i| {
            let s = &scene.sources[i];
            (source_name(&scene, i), s.kind, s.mesh, s.primitive, s.node, s.material)
        })
        .collect();
    let g = source_kind::GLTF_PRIMITIVE;
    assert_eq!(
        described,
        [("bunny", g, 0, 0, 0, NO_INDEX), ("bunny_1", g, 1, 0, 1, NO_INDEX), ("ground", g, 2, 0, 2, NO_INDEX)]
    );
    let a = triangles_of(&scene, 0);
    let b = triangles_of(&scene, 1);
    let ground = triangles_of(&scene, 2);
    assert_eq!((a.len(), b.len(), ground.len()), (3674, 3674, 2));
    assert_ne!(bounds(&a), bounds(&b), "the two instances must be placed differently");

    // Recompute vertices of the first triangle of each bunny by hand: the file's node matrix (as
    // f32, which is how glTF stores it) applied to the raw accessor data.
    let (json, bin) = glb_chunks(&std::fs::read(fixture("bunny_scene.glb")).unwrap());
    for (node, triangles) in [(0usize, &a), (1, &b)] {
        let m: Vec<f64> = json["nodes"][node]["matrix"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32 as f64)
            .collect();
        let primitive = &json["meshes"][node]["primitives"][0];
        let (position, indices) = (
            primitive["attributes"]["POSITION"].as_u64().unwrap() as usize,
            primitive["indices"].as_u64().unwrap() as usize,
        );
        let (index, first) = triangles[0];
        assert_eq!(index, 0);
        for (k, vertex) in first.iter().enumerate() {
            let i = accessor_element(&json, &bin, indices, k)[0] as usize;
            let p = accessor_element(&json, &bin, position, i);
            // Column-major: world[r] = m[r] x + m[4 + r] y + m[8 + r] z + m[12 + r].
            let expected: [f64; 3] =
                std::array::from_fn(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]);
            assert_close(*vertex, expected, 1e-6 * (1.0 + expected.iter().map(|x| x.abs()).fold(0.0, f64::max)));
        }
    }
    // The ground quad has no transform: y = -0.2 throughout.
    assert!(ground.iter().all(|(_, t)| t.iter().all(|v| (v[1] as f64 + 0.2).abs() < 1e-6)));
}

#[test]
fn box_gltf_root_rotation_is_applied() {
    let scene = import("Box.gltf");
    assert_eq!(scene.len(), 12);
    assert_eq!(scene.report.dropped_degenerate, 0);
    assert_eq!(input_name(&scene, 0), "Box.gltf");
    assert_eq!(scene.sources.len(), 1);
    let s = &scene.sources[0];
    // The mesh hangs off node 1, child of the rotated root node 0; it uses material 0.
    assert_eq!((s.kind, s.mesh, s.primitive, s.node, s.material), (source_kind::GLTF_PRIMITIVE, 0, 0, 1, 0));
    assert_eq!(source_name(&scene, 0), "Mesh");
    // Indices 0 1 2 name (-½,-½,½) (½,-½,½) (-½,½,½); the root matrix (columns (1,0,0), (0,0,-1),
    // (0,1,0)) maps (x, y, z) to (x, z, -y).
    assert_eq!(world(&scene)[0], [[-0.5, 0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, -0.5]]);
}

// ---------------------------------------------------------------------------------------------
// Small hand-made meshes

#[test]
fn obj_quads_ngons_groups_and_materials() {
    let scene = import("small/groups.obj");
    // Object: quad (2) + pentagon (3). Group: hexagon (4) + zero-area (dropped) + relative (1).
    assert_eq!(scene.len(), 10);
    assert_eq!(scene.report.dropped_degenerate, 1);
    assert_eq!(scene.report.warnings.len(), 1, "{:?}", scene.report.warnings);
    assert!(
        scene.report.warnings[0].ends_with("groups.obj: dropped 1 degenerate (zero-area) triangle"),
        "{}",
        scene.report.warnings[0]
    );
    assert_eq!(scene.sources.len(), 2);
    assert_eq!(source_name(&scene, 0), "quads_and_pentagon");
    assert_eq!(source_name(&scene, 1), "hexagon_group");
    let s: Vec<_> = scene.sources.iter().map(|s| (s.kind, s.mesh, s.primitive, s.node, s.material)).collect();
    let o = source_kind::OBJ_OBJECT;
    assert_eq!(s, [(o, 0, 0, NO_INDEX, 0), (o, 1, 0, NO_INDEX, 1)]); // red, blue
    let first = triangles_of(&scene, 0);
    let second = triangles_of(&scene, 1);
    assert_eq!(first.iter().map(|t| t.0).collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
    // Index 4 of the group is the zero-area `f 1 1 2`: dropped, but counted.
    assert_eq!(second.iter().map(|t| t.0).collect::<Vec<_>>(), [0, 1, 2, 3, 5]);
    // Fan triangulation: the quad 1 2 3 4 gives (1 2 3) and (1 3 4).
    assert_eq!(first[0].1, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
    assert_eq!(first[1].1, [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]);
    // `f -3 -2 -1` names the last three vertices.
    assert_eq!(second[4].1, [[1.0, 1.6, 1.0], [0.0, 1.6, 1.0], [-0.5, 0.8, 1.0]]);
    // Points, lines and the two-vertex face produce nothing and are not counted (OBJ).
    assert_eq!((scene.report.skipped_points, scene.report.skipped_lines), (0, 0));
}

#[test]
fn obj_missing_material_library_is_a_warning() {
    let scene = import("small/missing_mtl.obj");
    assert_eq!(scene.len(), 3);
    assert_eq!(scene.sources.len(), 1);
    assert_eq!(source_name(&scene, 0), "thing");
    assert_eq!(scene.sources[0].material, NO_INDEX);
    assert_eq!(scene.report.warnings.len(), 1, "{:?}", scene.report.warnings);
    assert!(scene.report.warnings[0].contains("does_not_exist.mtl"), "{}", scene.report.warnings[0]);
}

#[test]
fn gltf_primitive_modes() {
    let scene = import("small/modes.gltf");
    // Triangles (2, indexed u16), strip (4, not indexed), fan (4, indexed u8), triangles (2, not
    // indexed); points, lines and a line strip skipped. The strip's first two triangles and the
    // last list's two repeat triangles already seen: merged into them, with their provenance kept.
    assert_eq!(scene.len(), 8);
    let merged: Vec<_> = scene.duplicates.iter().map(|d| (d.triangle, d.source, d.index)).collect();
    assert_eq!(merged, [(0, 1, 0), (0, 3, 0), (1, 1, 1), (3, 3, 1)]);
    assert_eq!(scene.report.dropped_duplicates, 4);
    assert!(
        scene.report.warnings.iter().any(|w| w.contains("4 triangles have the same three vertices")),
        "{:?}",
        scene.report.warnings
    );
    assert_eq!(scene.report.skipped_points, 1);
    assert_eq!(scene.report.skipped_lines, 2);
    assert_eq!(scene.report.dropped_degenerate, 0);
    let s: Vec<_> = scene.sources.iter().map(|s| (s.mesh, s.primitive, s.node, s.material)).collect();
    // No scenes: the root node 0 is walked; the mesh sits on its child, node 1.
    assert_eq!(s, [(0, 0, 1, 0), (0, 1, 1, NO_INDEX), (0, 2, 1, NO_INDEX), (0, 6, 1, NO_INDEX)]);
    assert!((0..4).all(|i| source_name(&scene, i) == "modes"));
    let per_source: Vec<usize> = (0..4).map(|s| triangles_of(&scene, s).len()).collect();
    assert_eq!(per_source, [2, 2, 4, 0]);

    // Node 0 translates by (10, 0, 0).
    let p = |x: f32, y: f32, z: f32| [x + 10.0, y, z];
    let strip = triangles_of(&scene, 1);
    assert_eq!(strip.iter().map(|t| t.0).collect::<Vec<_>>(), [2, 3]);
    // Strip: (0 1 2), (1 3 2), (2 3 4), (3 5 4); the first two are the indexed list's.
    let list = triangles_of(&scene, 0);
    assert_eq!(list[0].1, [p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)]);
    assert_eq!(list[1].1, [p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)]);
    assert_eq!(strip[1].1, [p(1., 1., 0.), p(1., 2., 0.), p(0., 2., 0.)]);
    // Fan: (1 2 0), (2 3 0), ...
    let fan = triangles_of(&scene, 2);
    assert_eq!(fan[0].1, [p(1., 0., 1.), p(1., 1., 1.), p(0., 0., 1.)]);
    assert_eq!(fan[3].1, [p(-1., 1., 1.), p(-1., 0., 1.), p(0., 0., 1.)]);
}

#[test]
fn gltf_node_hierarchy_and_external_buffer() {
    let scene = import("small/hierarchy.gltf");
    // The default scene is scene 1 (root node 0); node 3 belongs to scene 0 only.
    assert_eq!(scene.len(), 2);
    let nodes: Vec<u32> = scene.sources.iter().map(|s| s.node).collect();
    assert_eq!(nodes, [1, 4]);
    assert!(scene.report.warnings.iter().any(|w| w.contains("2 scenes")), "{:?}", scene.report.warnings);
    let v = world(&scene);
    // Node 0: T(1,2,3) · Rz(90°) · S(2). Node 1 (matrix): scale x by 3, then translate z by 10.
    // Together (x, y, z) -> (1 - 2y, 2 + 6x, 23 + 2z).
    let tol = 1e-5;
    assert_close(v[0][0], [1.0, 2.0, 23.0], tol);
    assert_close(v[0][1], [1.0, 8.0, 23.0], tol);
    assert_close(v[0][2], [-1.0, 2.0, 23.0], tol);
    // Node 2 translates x by 5; node 4 rotates 180° about x: (x, y, z) -> (1 + 2y, 12 + 2x, 3 - 2z).
    assert_close(v[1][0], [1.0, 12.0, 3.0], tol);
    assert_close(v[1][1], [1.0, 14.0, 3.0], tol);
    assert_close(v[1][2], [3.0, 12.0, 3.0], tol);
}

#[test]
fn two_inputs_in_one_scene() {
    let scene = in_import_order(import_paths(&[fixture("small/groups.obj"), fixture("Box.gltf")]).unwrap());
    assert_eq!(scene.len(), 22);
    assert_eq!(scene.inputs.len(), 2);
    assert_eq!((input_name(&scene, 0), input_name(&scene, 1)), ("groups.obj", "Box.gltf"));
    assert_eq!((scene.inputs[0].triangle_count, scene.inputs[1].triangle_count), (10, 12));
    let inputs: Vec<u32> = scene.sources.iter().map(|s| s.input).collect();
    assert_eq!(inputs, [0, 0, 1]);
    for (i, p) in scene.provenance.iter().enumerate() {
        let expected_input = if i < 10 { 0 } else { 1 };
        assert_eq!(scene.sources[p.source as usize].input, expected_input, "triangle {i}");
    }
    let hash = |name: &str| *blake3::hash(&std::fs::read(fixture(name)).unwrap()).as_bytes();
    assert_eq!(scene.inputs[0].file_hash, hash("small/groups.obj"));
    assert_eq!(scene.inputs[1].file_hash, hash("Box.gltf"));

    // The same through a builder.
    let mut builder = SceneBuilder::new();
    import_path(&mut builder, &fixture("Box.gltf")).unwrap();
    import_path(&mut builder, &fixture("bunny.obj")).unwrap();
    let scene = in_import_order(builder.finish().unwrap());
    assert_eq!(scene.len(), 12 + 3674);
    assert_eq!((input_name(&scene, 0), input_name(&scene, 1)), ("Box.gltf", "bunny.obj"));
}

#[test]
fn morton_order_is_a_permutation_of_import_order() {
    // Two inputs, so that the order mixes sources; the bunny has no duplicates, the groups none.
    let scene = import_paths(&[fixture("bunny.obj"), fixture("small/groups.obj")]).unwrap();
    let imported = in_import_order(scene.clone());
    // Every (source, index) once: a permutation.
    let mut seen: Vec<(u32, u32)> = scene.provenance.iter().map(|p| (p.source, p.index)).collect();
    seen.sort_unstable();
    seen.dedup();
    assert_eq!(seen.len(), scene.len());
    // The stored order is the Morton order of the import order, triangle for triangle.
    let order = vlf_bake::order::morton_order(&imported.vertices());
    let expected: Vec<[[f32; 3]; 3]> = order.iter().map(|&k| imported.triangles[k as usize].v).collect();
    assert_eq!(scene.vertices(), expected);
    assert_ne!(scene.vertices(), imported.vertices(), "the bunny's import order is not Morton order");
    // Neighbours in the file are close in space: the mean distance between consecutive
    // centroids falls well below import order's.
    let mean_step = |s: &Scene| {
        let c: Vec<[f64; 3]> =
            s.vertices().iter().map(|t| std::array::from_fn(|i| (t[0][i] + t[1][i] + t[2][i]) as f64 / 3.0)).collect();
        c.windows(2).map(|w| (0..3).map(|i| (w[1][i] - w[0][i]).powi(2)).sum::<f64>().sqrt()).sum::<f64>()
            / (c.len() - 1) as f64
    };
    let (morton, import) = (mean_step(&scene), mean_step(&imported));
    assert!(morton < 0.5 * import, "mean step between neighbours: Morton {morton}, import {import}");
}

#[test]
fn format_is_sniffed_when_the_extension_is_unknown_and_case_is_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let copy = |from: &str, to: &str| {
        let target = dir.path().join(to);
        std::fs::copy(fixture(from), &target).unwrap();
        target
    };
    let glb = copy("bunny_scene.glb", "scene.bin3");
    let gltf = copy("Box.gltf", "box.json");
    let obj = copy("bunny.obj", "bunny.mesh");
    let upper = copy("Box.gltf", "BOX.GLTF");
    let upper_obj = copy("small/missing_mtl.obj", "THING.OBJ");
    assert_eq!(import_paths(&[glb]).unwrap().len(), 7350);
    assert_eq!(import_paths(&[gltf]).unwrap().len(), 12);
    assert_eq!(import_paths(&[obj]).unwrap().len(), 3674);
    assert_eq!(import_paths(&[upper]).unwrap().len(), 12);
    assert_eq!(import_paths(&[upper_obj]).unwrap().len(), 3);
    let e = import_err("bad/unknown.xyz");
    assert!(matches!(e, ImportError::UnknownFormat { .. }), "{e:?}");
}

// ---------------------------------------------------------------------------------------------
// Bad inputs: each gives its own error, naming the file.

#[test]
fn obj_nan_vertex() {
    match import_err("bad/nan_vertex.obj") {
        ImportError::NonFinite { source_name, triangle, vertex, value, .. } => {
            assert!(source_name.contains("spiky"), "{source_name}");
            assert_eq!((triangle, vertex), (0, 2));
            assert!(value[0].is_nan());
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn obj_huge_vertex() {
    let e = import_err("bad/huge_vertex.obj");
    assert!(matches!(&e, ImportError::TooLarge { source_name, .. } if source_name.contains("far_away")), "{e:?}");
    assert!(e.to_string().contains("vertex 2 coordinate [0.0, 1e30, 0.0] exceeds ±1e18"), "{e}");
    // A coordinate beyond f32 is shown as written, not as `inf`.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("farther.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv -1e308 0.5 0\nf 1 2 3\n").unwrap();
    let e = import_paths(&[path]).unwrap_err().to_string();
    assert!(e.contains("vertex 2 coordinate [-1e308, 0.5, 0.0] exceeds ±1e18"), "{e}");
}

#[test]
fn obj_with_a_byte_order_mark_and_unknown_statements() {
    let dir = tempfile::tempdir().unwrap();
    // A byte-order mark before the first vertex: four vertices, the face on the first three. It
    // once read as an unknown word, so that the line was dropped and the face took vertices 2-4.
    let path = dir.path().join("bom.obj");
    std::fs::write(&path, "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n").unwrap();
    let scene = import_paths(&[path]).unwrap();
    assert_eq!(world(&scene), [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);
    // Lines that are no statement are skipped, and said to be.
    let path = dir.path().join("foreign.obj");
    std::fs::write(&path, "# made by hand\nv 0 0 0\nvv 1 0 0\nv 1 0 0\nfoo bar\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = import_paths(&[path]).unwrap();
    assert_eq!(world(&scene), [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
    assert!(
        scene.report.warnings.iter().any(|w| w.ends_with(
            "foreign.obj: 2 line(s) hold no OBJ statement and were skipped; the first, line 3, reads \"vv 1 0 0\""
        )),
        "{:?}",
        scene.report.warnings
    );
}

#[test]
fn obj_face_index_out_of_range() {
    match import_err("bad/out_of_range.obj") {
        ImportError::IndexOutOfRange { location, index, count, .. } => {
            assert_eq!((index, count), (7, 3));
            assert!(location.contains("line 6") && location.contains("broken"), "{location}");
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn obj_without_triangles() {
    for name in ["bad/only_vertices.obj", "bad/all_degenerate.obj"] {
        let e = import_err(name);
        assert!(matches!(e, ImportError::NoTriangles { .. }), "{name}: {e:?}");
    }
    for name in ["bad/empty.obj", "bad/empty.gltf", "bad/empty.glb"] {
        let e = import_err(name);
        assert!(matches!(e, ImportError::Empty { .. }), "{name}: {e:?}");
    }
}

#[test]
fn obj_that_is_not_a_mesh() {
    let e = import_err("bad/x.obj");
    assert!(matches!(&e, ImportError::Obj { message, .. } if message.contains("not an OBJ")), "{e:?}");
    let e = import_err("bad/not_utf8.obj");
    assert!(matches!(&e, ImportError::Obj { message, .. } if message.contains("UTF-8")), "{e:?}");
    let e = import_err("bad/malformed_face.obj");
    assert!(matches!(&e, ImportError::Obj { message, .. } if message.contains("line 5")), "{e:?}");
}

#[test]
fn gltf_missing_external_buffer() {
    let e = import_err("bad/missing_buffer.gltf");
    assert!(matches!(&e, ImportError::Gltf { message, .. } if message.contains("missing_buffer.bin")), "{e:?}");
}

#[test]
fn gltf_draco_and_unknown_required_extensions() {
    match import_err("bad/draco.gltf") {
        ImportError::UnsupportedExtension { location, extension, .. } => {
            assert_eq!((location.as_str(), extension.as_str()), ("mesh 0 primitive 0", "KHR_draco_mesh_compression"));
        }
        e => panic!("{e:?}"),
    }
    match import_err("bad/required_unknown.gltf") {
        ImportError::UnsupportedExtension { location, extension, .. } => {
            assert_eq!((location.as_str(), extension.as_str()), ("document", "EXT_made_up_geometry"));
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn gltf_index_out_of_range() {
    match import_err("bad/index_out_of_range.gltf") {
        ImportError::IndexOutOfRange { location, index, count, .. } => {
            assert_eq!((location.as_str(), index, count), ("mesh 0 primitive 0", 5, 3));
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn gltf_structural_errors() {
    for (name, needle) in [
        ("bad/accessor_overrun.gltf", "overrun buffer view 0"),
        ("bad/node_cycle.gltf", "reached twice"),
        ("bad/truncated.glb", "GLB"),
        ("bad/not_json.gltf", "JSON"),
    ] {
        let e = import_err(name);
        assert!(matches!(&e, ImportError::Gltf { message, .. } if message.contains(needle)), "{name}: {e:?}");
    }
    let e = import_err("bad/points_only.gltf");
    assert!(matches!(e, ImportError::NoTriangles { .. }), "{e:?}");
}

#[test]
fn missing_file_and_no_inputs() {
    let e = import_err("bad/does_not_exist.obj");
    assert!(matches!(e, ImportError::Io { .. }), "{e:?}");
    let none: [&Path; 0] = [];
    assert!(matches!(import_paths(&none), Err(ImportError::NoTriangles { .. })));
}

// ---------------------------------------------------------------------------------------------
// Hostile inputs: errors, never panics.

/// A one-triangle glTF document with embedded data, for mutation.
fn tiny_gltf() -> Value {
    use std::io::Write;
    let mut bin = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for c in v {
            bin.write_all(&c.to_le_bytes()).unwrap();
        }
    }
    for i in [0u16, 1, 2, 0] {
        bin.write_all(&i.to_le_bytes()).unwrap();
    }
    let b64 = base64_encode(&bin);
    json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "buffers": [{"byteLength": 44, "uri": format!("data:application/octet-stream;base64,{b64}")}]
    })
}

fn base64_encode(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn import_json(dir: &Path, name: &str, doc: &Value) -> Result<Scene, ImportError> {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
    import_paths(&[path])
}

#[test]
fn hostile_gltf_documents_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(import_json(dir.path(), "ok.gltf", &tiny_gltf()).unwrap().len(), 1);
    type Edit = fn(&mut Value);
    let cases: &[(&str, Edit)] = &[
        ("position accessor out of range", |d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9)),
        ("indices accessor out of range", |d| d["meshes"][0]["primitives"][0]["indices"] = json!(9)),
        ("zero count", |d| d["accessors"][0]["count"] = json!(0)),
        ("huge count", |d| d["accessors"][0]["count"] = json!(u64::MAX)),
        ("huge offset", |d| d["accessors"][0]["byteOffset"] = json!(u64::MAX - 3)),
        ("huge view offset", |d| d["bufferViews"][0]["byteOffset"] = json!(u64::MAX - 3)),
        ("huge view length", |d| d["bufferViews"][0]["byteLength"] = json!(u64::MAX)),
        ("stride too small", |d| d["bufferViews"][0]["byteStride"] = json!(4)),
        ("stride zero", |d| d["bufferViews"][0]["byteStride"] = json!(0)),
        ("float indices", |d| d["accessors"][1]["componentType"] = json!(5126)),
        ("vec3 indices", |d| d["accessors"][1]["type"] = json!("VEC3")),
        ("vec2 positions", |d| d["accessors"][0]["type"] = json!("VEC2")),
        ("short positions", |d| d["accessors"][0]["componentType"] = json!(5123)),
        ("bad mode", |d| d["meshes"][0]["primitives"][0]["mode"] = json!(9)),
        ("missing node", |d| d["scenes"][0]["nodes"] = json!([5])),
        ("self child", |d| d["nodes"][0]["children"] = json!([0])),
        ("two parents", |d| {
            d["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
            d["scenes"][0]["nodes"] = json!([0, 1]);
        }),
        ("missing buffer view", |d| d["accessors"][0]["bufferView"] = json!(7)),
        ("short buffer", |d| d["buffers"][0]["byteLength"] = json!(4000)),
        ("bad base64", |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@")),
        ("invalid percent-encoding", |d| d["buffers"][0]["uri"] = json!("%FF%FE.bin")),
        ("http uri", |d| d["buffers"][0]["uri"] = json!("http://example.invalid/x.bin")),
        ("sparse zero count", |d| {
            d["accessors"][0]["sparse"] = json!({"count": 0, "indices": {"bufferView": 1, "componentType": 5123},
                "values": {"bufferView": 0}});
        }),
        ("sparse only, huge", |d| {
            d["accessors"][0].as_object_mut().unwrap().remove("bufferView");
            d["accessors"][0]["count"] = json!(1u64 << 40);
            d["accessors"][0]["sparse"] = json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                "values": {"bufferView": 0}});
        }),
        ("sparse values overrun", |d| {
            d["accessors"][0]["sparse"] = json!({"count": 3, "indices": {"bufferView": 1, "componentType": 5123},
                "values": {"bufferView": 0, "byteOffset": 12}});
        }),
        ("index out of range", |d| d["accessors"][0]["count"] = json!(2)),
        ("meshopt required", |d| {
            d["extensionsRequired"] = json!(["EXT_meshopt_compression"]);
            d["bufferViews"][0]["extensions"] = json!({"EXT_meshopt_compression": {}});
        }),
        ("no asset", |d| {
            d.as_object_mut().unwrap().remove("asset");
        }),
        ("array", |d| *d = json!([1, 2, 3])),
    ];
    for (what, edit) in cases {
        let mut doc = tiny_gltf();
        edit(&mut doc);
        let result = import_json(dir.path(), "hostile.gltf", &doc);
        assert!(result.is_err(), "{what}: imported {} triangles", result.unwrap().len());
        let e = result.unwrap_err();
        assert!(e.to_string().contains("hostile.gltf"), "{what}: {e}");
        if *what == "meshopt required" {
            assert!(
                matches!(&e, ImportError::UnsupportedExtension { location, .. } if location == "mesh 0 primitive 0"),
                "{e:?}"
            );
        }
        if *what == "index out of range" {
            assert!(matches!(e, ImportError::IndexOutOfRange { index: 2, count: 2, .. }), "{what}: {e:?}");
        }
        if std::env::var_os("VLF_SHOW_ERRORS").is_some() {
            eprintln!("{what}: {e}");
        }
    }

    // Harmless deviations are accepted: no POSITION bounds, a geometry-neutral required extension,
    // a primitive without POSITION (skipped with a warning).
    let mut doc = tiny_gltf();
    doc["accessors"][0].as_object_mut().unwrap().remove("min");
    doc["accessors"][0].as_object_mut().unwrap().remove("max");
    doc["extensionsUsed"] = json!(["KHR_materials_unlit"]);
    doc["extensionsRequired"] = json!(["KHR_materials_unlit"]);
    doc["meshes"][0]["primitives"].as_array_mut().unwrap().push(json!({"attributes": {"NORMAL": 0}, "indices": 1}));
    let scene = import_json(dir.path(), "lenient.gltf", &doc).unwrap();
    assert_eq!(scene.len(), 1);
    assert!(scene.report.warnings.iter().any(|w| w.contains("no POSITION")), "{:?}", scene.report.warnings);

    // A sparse accessor without a buffer view: three zero vertices, of which 1 and 2 are replaced
    // (indices 1, 2 from byte 2 of the index view; values from vertex 1 of the position view).
    let mut doc = tiny_gltf();
    let position = doc["accessors"][0].as_object_mut().unwrap();
    position.remove("bufferView");
    position.insert(
        "sparse".into(),
        json!({"count": 2, "indices": {"bufferView": 1, "byteOffset": 2, "componentType": 5123},
            "values": {"bufferView": 0, "byteOffset": 12}}),
    );
    let scene = import_json(dir.path(), "sparse.gltf", &doc).unwrap();
    assert_eq!(world(&scene), [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
}

#[test]
fn a_broken_primitive_is_refused_before_the_triangles_are_counted_or_made() {
    // Mesh 0: 800 primitives of 2²⁴ − 1 sparse zeros, 5,592,405 triangles each, 4.47 · 10⁹ in all,
    // past the 2³² − 1 a field holds. Mesh 1: a POSITION accessor whose bytes lie past its buffer.
    // The count that refuses the first must see the second as the import does: a broken file,
    // named as such, not one primitive of zero triangles beside too many others.
    let dir = tempfile::tempdir().unwrap();
    let mut doc = tiny_gltf();
    doc["accessors"].as_array_mut().unwrap().extend([
        json!({"componentType": 5126, "count": 16777215, "type": "VEC3",
            "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}}),
        json!({"bufferView": 0, "byteOffset": 24, "componentType": 5126, "count": 3, "type": "VEC3"}),
    ]);
    doc["meshes"] = json!([
        {"primitives": vec![json!({"attributes": {"POSITION": 2}}); 800]},
        {"primitives": [{"attributes": {"POSITION": 3}}]}
    ]);
    doc["nodes"] = json!([{"mesh": 0}, {"mesh": 1}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    let e = import_json(dir.path(), "broken.gltf", &doc).unwrap_err();
    let ImportError::Gltf { message, .. } = &e else { panic!("not the broken accessor: {e}") };
    assert!(message.starts_with("mesh 1 primitive 0: POSITION accessor 3: "), "{message}");
    // Without the broken mesh, the count refuses the rest.
    doc["nodes"] = json!([{"mesh": 0}]);
    doc["scenes"] = json!([{"nodes": [0]}]);
    let e = import_json(dir.path(), "many.gltf", &doc).unwrap_err();
    assert!(matches!(e, ImportError::InstancesTooManyTriangles { triangles: 4_473_924_000, .. }), "{e}");
}

#[test]
fn hostile_obj_texts_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("huge texture index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/9223372036854775807 2/1 3/1\n"),
        ("very negative texture index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-9223372036854775808 2/1 3/1\n"),
        ("huge normal index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//4611686018427387904 2//1 3//1\n"),
        ("zero index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
        ("relative index before the start", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
        ("four components", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n"),
        ("empty face", "v 0 0 0\nf\n"),
        ("w zero", "v 0 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("five numbers", "v 0 0 0 1 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("two numbers", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("usemtl without name", "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n"),
        ("infinite", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n"),
    ];
    for (what, text) in cases {
        let path = dir.path().join("hostile.obj");
        std::fs::write(&path, text).unwrap();
        let result = import_paths(&[&path]);
        assert!(result.is_err(), "{what}: imported {} triangles", result.unwrap().len());
        let e = result.unwrap_err();
        assert!(e.to_string().contains("hostile.obj"), "{what}: {e}");
        if std::env::var_os("VLF_SHOW_ERRORS").is_some() {
            eprintln!("{what}: {e}");
        }
    }

    // A material library whose colour line is short (tobj's own MTL parser panics on it) and a
    // usemtl naming an undefined material: imported, with a warning for the latter.
    std::fs::write(dir.path().join("short.mtl"), "newmtl a\nKd 1 2\nnewmtl b\n").unwrap();
    let path = dir.path().join("materials.obj");
    std::fs::write(&path, "mtllib short.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\nusemtl zz\nf 1 3 2\n")
        .unwrap();
    let scene = import_paths(&[&path]).unwrap();
    // `f 1 3 2` is `f 1 2 3` wound the other way: merged into it, its source kept.
    assert_eq!((scene.len(), scene.duplicates.len()), (1, 1));
    assert_eq!(scene.duplicates[0].source, 1);
    let materials: Vec<u32> = scene.sources.iter().map(|s| s.material).collect();
    assert_eq!(materials, [1, NO_INDEX]);
    assert!(scene.report.warnings.iter().any(|w| w.contains("\"zz\"")), "{:?}", scene.report.warnings);
}

/// Deterministic mutations of every small fixture (truncations and byte changes): whatever the
/// importers make of them, they return.
#[test]
fn mutated_fixtures_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for name in ["small/groups.obj", "small/modes.gltf", "small/hierarchy.gltf", "Box.gltf", "bunny_scene.glb"] {
        let original = std::fs::read(fixture(name)).unwrap();
        let ext = Path::new(name).extension().unwrap().to_str().unwrap();
        std::fs::copy(fixture("small/hierarchy.bin"), dir.path().join("hierarchy.bin")).unwrap();
        for round in 0..150 {
            let mut bytes = original.clone();
            if round % 3 == 0 {
                bytes.truncate(next() as usize % bytes.len());
            } else {
                // glTF: hit the JSON (where the structure is) more often than the binary data.
                let span = if ext == "glb" { 2000.min(bytes.len()) } else { bytes.len() };
                for _ in 0..1 + next() % 4 {
                    let at = next() as usize % span;
                    bytes[at] = b"0123456789-:,[]{}\"e./ \n"[next() as usize % 23];
                }
            }
            let path = dir.path().join(format!("mutant.{ext}"));
            std::fs::write(&path, &bytes).unwrap();
            let _ = import_paths(&[&path]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Materials, cameras and lights (formats/vlf.md §5.10–5.12)

/// The material record of `scene` named `name`.
fn material<'a>(scene: &'a Scene, name: &str) -> &'a vlf_format::MaterialRecord {
    scene
        .materials
        .iter()
        .find(|m| string(scene, m.name_offset, m.name_length) == name)
        .unwrap_or_else(|| panic!("no material {name:?}"))
}

fn assert_rgb(actual: [f32; 3], expected: [f32; 3]) {
    for k in 0..3 {
        assert!((actual[k] - expected[k]).abs() < 1e-6, "{actual:?} != {expected:?}");
    }
}

#[test]
fn obj_materials_map_mtl_statements_to_the_whitted_model() {
    let scene = import("cornell/cornell.obj");
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);
    let names: Vec<&str> = scene.materials.iter().map(|m| string(&scene, m.name_offset, m.name_length)).collect();
    assert_eq!(names, ["white", "red", "green", "yellow", "lamp", "mirror", "glass"]);
    assert!(scene.materials.iter().enumerate().all(|(i, m)| m.input == 0 && m.index == i as u32));
    // Every source's material index names the record of the material its `usemtl` gave.
    for (s, source) in scene.sources.iter().enumerate() {
        let m = &scene.materials[source.material as usize];
        let expected = match source_name(&scene, s) {
            "floor" | "ceiling" | "back" => "white",
            "left" => "red",
            "right" => "green",
            "lamp" => "lamp",
            "mirror_block" => "mirror",
            "yellow_block" => "yellow",
            "glass_sphere" => "glass",
            other => panic!("unexpected source {other}"),
        };
        assert_eq!(string(&scene, m.name_offset, m.name_length), expected);
    }
    // Only Kd: the defaults (no highlight, mirror, transmission or emission; ior 1).
    let white = material(&scene, "white");
    assert_rgb(white.diffuse, [0.75, 0.75, 0.72]);
    assert_eq!(
        (white.specular, white.reflection, white.transmission, white.emission),
        ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3])
    );
    assert_eq!((white.shininess, white.ior), (1.0, 1.0));
    // illum 3: Ks is both the highlight and the mirror.
    let mirror = material(&scene, "mirror");
    assert_rgb(mirror.reflection, [0.85; 3]);
    assert_rgb(mirror.specular, [0.85; 3]);
    assert_eq!(mirror.shininess, 800.0);
    // d 0.05: 5% of Kd stays diffuse, 95% of Tf is transmitted, Ni is the index of refraction.
    let glass = material(&scene, "glass");
    assert_rgb(glass.diffuse, [0.05; 3]);
    assert_rgb(glass.transmission, [0.95; 3]);
    assert_rgb(glass.reflection, [0.1; 3]);
    assert_eq!(glass.ior, 1.5);
    // illum 1: no highlights; Ke is emission.
    let lamp = material(&scene, "lamp");
    assert_rgb(lamp.emission, [1.0, 1.0, 0.95]);
    assert_eq!(lamp.specular, [0.0; 3]);
    // OBJ has no cameras or lights.
    assert!(scene.cameras.is_empty() && scene.lights.is_empty());
}

#[test]
fn gltf_materials_cameras_and_lights_are_imported_in_world_space() {
    use vlf_format::{camera_kind, light_kind};
    let scene = import("cornell/cornell.gltf");
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);
    assert_eq!(scene.materials.len(), 7);
    // metallic 1, roughness 0: a mirror of the base colour, nothing diffuse.
    let mirror = material(&scene, "mirror");
    assert_rgb(mirror.reflection, [0.85; 3]);
    assert_rgb(mirror.diffuse, [0.0; 3]);
    assert_eq!(mirror.shininess, 4096.0);
    // KHR_materials_transmission and KHR_materials_ior.
    let glass = material(&scene, "glass");
    assert_rgb(glass.transmission, [1.0; 3]);
    assert_rgb(glass.diffuse, [0.0; 3]);
    assert_rgb(glass.reflection, [0.04; 3]);
    assert_eq!(glass.ior, 1.5);
    // A rough dielectric: all diffuse, a dim broad highlight, no mirror.
    let red = material(&scene, "red");
    assert_rgb(red.diffuse, [0.7, 0.12, 0.1]);
    assert_rgb(red.specular, [0.04; 3]);
    assert_eq!((red.reflection, red.shininess), ([0.0; 3], 1.0));
    assert_rgb(material(&scene, "lamp").emission, [1.0, 1.0, 0.95]);

    assert_eq!(scene.cameras.len(), 1);
    let c = &scene.cameras[0];
    assert_eq!((c.kind, c.camera, c.input), (camera_kind::PERSPECTIVE, 0, 0));
    assert_eq!(string(&scene, c.name_offset, c.name_length), "front");
    assert_eq!((c.position, c.forward, c.up), ([0.0, 12.0, 48.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]));
    assert_eq!((c.yfov, c.znear, c.zfar), (0.66, 0.1, 0.0));
    assert!((c.aspect_ratio - 4.0 / 3.0).abs() < 1e-6);

    assert_eq!(scene.lights.len(), 2);
    let (lamp, fill) = (&scene.lights[0], &scene.lights[1]);
    assert_eq!(string(&scene, lamp.name_offset, lamp.name_length), "lamp");
    assert_eq!((lamp.kind, lamp.light, lamp.intensity), (light_kind::SPOT, 0, 400.0));
    assert_eq!((lamp.inner_cone, lamp.outer_cone, lamp.position), (0.8, 1.4, [0.0, 23.0, -2.0]));
    // The node's rotation turns its -z axis straight down.
    assert_close(lamp.direction, [0.0, -1.0, 0.0], 1e-6);
    assert_eq!((fill.kind, fill.position, fill.color), (light_kind::POINT, [-10.0, 16.0, 40.0], [0.85, 0.9, 1.0]));
}

#[test]
fn a_camera_and_a_light_follow_their_nodes_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = tiny_gltf();
    let half = std::f64::consts::FRAC_1_SQRT_2;
    // A parent translated by (1, 2, 3) and turned 90° about y (-z becomes -x) holds the camera;
    // its child, translated by 5 along the parent's z, holds a directional light.
    doc["nodes"] = json!([
        {"mesh": 0},
        {"translation": [1, 2, 3], "rotation": [0, half, 0, half], "camera": 0, "children": [2]},
        {"translation": [0, 0, 5], "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    doc["cameras"] =
        json!([{"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1.5, "znear": 0, "zfar": 100}}]);
    doc["extensions"] =
        json!({"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3, "name": "sun"}]}});
    let scene = import_json(dir.path(), "placed.gltf", &doc).unwrap();
    assert!(scene.report.warnings.is_empty(), "{:?}", scene.report.warnings);
    let c = &scene.cameras[0];
    assert_eq!((c.kind, c.node, c.xmag, c.ymag, c.yfov), (vlf_format::camera_kind::ORTHOGRAPHIC, 1, 2.0, 1.5, 0.0));
    assert_close(c.position, [1.0, 2.0, 3.0], 1e-6);
    assert_close(c.forward, [-1.0, 0.0, 0.0], 1e-6);
    assert_close(c.up, [0.0, 1.0, 0.0], 1e-6);
    let l = &scene.lights[0];
    assert_eq!((l.kind, l.node, l.intensity, l.color), (vlf_format::light_kind::DIRECTIONAL, 2, 3.0, [1.0; 3]));
    assert_eq!(string(&scene, l.name_offset, l.name_length), "sun");
    // The child's +z is the parent's +x.
    assert_close(l.position, [6.0, 2.0, 3.0], 1e-6);
    assert_close(l.direction, [-1.0, 0.0, 0.0], 1e-6);
}

#[test]
fn unusable_cameras_and_lights_are_skipped_with_a_warning_and_bad_indices_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = tiny_gltf();
    doc["nodes"] = json!([
        {"mesh": 0},
        {"camera": 0},
        {"camera": 1, "scale": [0, 0, 0]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    doc["scenes"] = json!([{"nodes": [0, 1, 2, 3]}]);
    doc["cameras"] = json!([
        // Declares a perspective camera but gives orthographic parameters (the gltf crate would panic).
        {"type": "perspective", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0, "zfar": 10}},
        {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}
    ]);
    doc["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}}
    ]}});
    let scene = import_json(dir.path(), "bad.gltf", &doc).unwrap();
    assert!(scene.cameras.is_empty() && scene.lights.is_empty());
    let w = &scene.report.warnings;
    assert_eq!(w.len(), 3, "{w:?}");
    assert!(w[0].contains("node 1: camera 0 skipped"), "{w:?}");
    assert!(w[1].contains("node 2: camera 1 skipped"), "{w:?}");
    assert!(w[2].contains("node 3: light 0 skipped"), "{w:?}");

    doc["nodes"][3] = json!({"extensions": {"KHR_lights_punctual": {"light": 4}}});
    let e = import_json(dir.path(), "bad.gltf", &doc).unwrap_err().to_string();
    assert!(e.contains("bad.gltf") && e.contains("nodes[3]") && e.contains("light"), "{e}");
}

#[test]
fn a_malformed_mtl_statement_is_ignored_with_a_warning_naming_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    std::fs::write(dir.path().join("t.obj"), obj).unwrap();
    for (mtl, says) in [
        ("newmtl a\nKd 1 nan 0\n", "line 2"),
        ("newmtl a\nKd 1 1\n", "line 2"),
        ("newmtl a\nKd spectral file.rfl\n", "spectral"),
        ("newmtl a\n\nd 1.5\n", "line 3"),
        ("newmtl a\nNi 0\n", "Ni"),
        ("newmtl a\nillum 2.5\n", "illum"),
        ("newmtl a\nKs -1 0 0\n", "non-negative"),
    ] {
        std::fs::write(dir.path().join("m.mtl"), mtl).unwrap();
        let scene = import_paths(&[dir.path().join("t.obj")]).unwrap();
        // The material is kept, with its defaults where the statement was.
        assert_eq!(scene.sources[0].material, 0, "{mtl:?}");
        let m = &scene.materials[0];
        assert_eq!((m.diffuse, m.specular, m.ior, m.transmission), ([0.8; 3], [0.0; 3], 1.0, [0.0; 3]), "{mtl:?}");
        let w = scene.report.warnings.join("\n");
        assert!(w.contains("m.mtl") && w.contains(says) && w.contains("ignored"), "{mtl:?}: {w}");
    }
    // A newmtl without a name would renumber the materials: the library is not used.
    std::fs::write(dir.path().join("m.mtl"), "newmtl\nnewmtl a\n").unwrap();
    let scene = import_paths(&[dir.path().join("t.obj")]).unwrap();
    assert!(scene.materials.is_empty());
    assert_eq!(scene.sources[0].material, NO_INDEX);
    // Tr is 1 - d; the later of d and Tr wins; a single number is a grey; textures are noted.
    std::fs::write(dir.path().join("m.mtl"), "Kd 9 9 9\nnewmtl a\nd 0.2\nTr 0.25\nKd 0.5\nTf 0.5 1 1\nmap_Kd x.png\n")
        .unwrap();
    let scene = import_paths(&[dir.path().join("t.obj")]).unwrap();
    let m = &scene.materials[0];
    assert_rgb(m.diffuse, [0.375; 3]);
    assert_rgb(m.transmission, [0.125, 0.25, 0.25]);
    assert!(scene.report.warnings.iter().any(|w| w.contains("texture")), "{:?}", scene.report.warnings);
}

// ---------------------------------------------------------------------------------------------
// Files judged by their first bytes and their size before they are read whole

/// A sparse file of `size` bytes at `dir/name` that starts with `start` (zeros after it).
fn sparse(dir: &Path, name: &str, start: &[u8], size: u64) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, start).unwrap();
    std::fs::File::options().write(true).open(&path).unwrap().set_len(size).unwrap();
    path
}

/// A tebibyte: more than any machine running these tests can read into memory.
const TIB: u64 = 1 << 40;

#[test]
fn a_huge_mesh_is_refused_by_its_first_bytes_without_reading_it() {
    let dir = tempfile::tempdir().unwrap();
    let message = |path: &Path| import_paths(&[path]).unwrap_err().to_string();
    let glb = sparse(dir.path(), "zeros.glb", b"", TIB);
    assert!(
        message(&glb).ends_with("not a GLB file: it does not start with the GLB magic \"glTF\""),
        "{}",
        message(&glb)
    );
    let gltf = sparse(dir.path(), "zeros.gltf", b"", TIB);
    assert!(message(&gltf).contains("neither glTF JSON nor GLB"), "{}", message(&gltf));
    // JSON's grammar is checked as far as the first bytes go: a NUL byte is no JSON.
    let gltf = sparse(dir.path(), "brace_then_zeros.gltf", b"{\"asset\": ", TIB);
    assert!(
        message(&gltf).ends_with("the JSON does not parse: expected value at line 1 column 11"),
        "{}",
        message(&gltf)
    );
    let mut start = tiny_glb();
    start[8..12].copy_from_slice(&(1u32 << 31).to_le_bytes());
    let json_len = u32::from_le_bytes(start[12..16].try_into().unwrap()) as usize;
    start.truncate(21);
    start[12..16].copy_from_slice(&(1u32 << 30).to_le_bytes());
    let glb = sparse(dir.path(), "json_then_zeros.glb", &start, 1 << 31);
    assert!(
        message(&glb).ends_with("the JSON does not parse: key must be a string at line 1 column 2"),
        "{}",
        message(&glb)
    );
    assert!(json_len > 4);
    let obj = sparse(dir.path(), "zeros.obj", b"", TIB);
    assert!(
        message(&obj).ends_with("not a valid OBJ file: not text (a NUL byte on line 1); is this an OBJ file?"),
        "{}",
        message(&obj)
    );
    let obj = sparse(dir.path(), "vertex_then_zeros.obj", b"v 0 0 0\nv 1 0 0\n", TIB);
    assert!(message(&obj).contains("not text (a NUL byte on line 3)"), "{}", message(&obj));
    // A GLB header cannot give a length past 4 GiB: a file larger is refused by its header.
    let glb = sparse(dir.path(), "huge.glb", b"glTF\x02\0\0\0\x40\0\0\0", TIB);
    assert!(
        message(&glb).contains("gives its length as 64 bytes, but the file has 1099511627776"),
        "{}",
        message(&glb)
    );
}

#[test]
fn a_mesh_larger_than_memory_is_refused_naming_its_size_and_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    // A start that is JSON as far as the first bytes go (spaces), then zeros.
    let gltf = sparse(dir.path(), "big.gltf", &[b"{".as_slice(), &[b' '; 70_000]].concat(), TIB);
    let e = import_paths(&[&gltf]).unwrap_err();
    let ImportError::Io { path, error } = &e else { panic!("{e:?}") };
    assert_eq!(path, &gltf);
    assert_eq!(error.kind(), std::io::ErrorKind::OutOfMemory);
    let text = e.to_string();
    assert!(text.contains("big.gltf: it is 1.0 TiB (1099511627776 bytes), more than the "), "{text}");
    assert!(text.contains(" of memory it may be read into ("), "{text}");

    // An external buffer as large: refused the same way, naming the buffer.
    sparse(dir.path(), "big.bin", b"", TIB);
    let mut doc = tiny_gltf();
    doc["buffers"][0] = json!({"byteLength": TIB, "uri": "big.bin"});
    let e = import_json(dir.path(), "big_buffer.gltf", &doc).unwrap_err().to_string();
    assert!(e.contains("buffer 0: cannot read external file \"big.bin\""), "{e}");
    assert!(e.contains("it is 1.0 TiB (1099511627776 bytes), more than the "), "{e}");
}

#[test]
fn a_material_library_that_is_not_text_is_a_warning_read_no_further() {
    let dir = tempfile::tempdir().unwrap();
    sparse(dir.path(), "zeros.mtl", b"", TIB);
    sparse(dir.path(), "half.mtl", b"newmtl a\nKd 1 0 0\n", TIB);
    for library in ["zeros.mtl", "half.mtl"] {
        let path = dir.path().join("with_library.obj");
        std::fs::write(&path, format!("mtllib {library}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")).unwrap();
        let scene = import_paths(&[&path]).unwrap();
        assert_eq!(scene.len(), 1);
        let warnings = &scene.report.warnings;
        assert!(
            warnings.iter().any(|w| w.contains(&format!("material library \"{library}\"")) && w.contains("a NUL byte")),
            "{warnings:?}"
        );
    }
}

#[test]
fn a_node_transform_beyond_f32_is_blamed_on_the_node() {
    let dir = tempfile::tempdir().unwrap();
    type Edit = fn(&mut Value);
    let cases: &[(Edit, &str)] = &[
        (
            |d| d["nodes"][0]["scale"] = json!([1e39, 1e39, 1e39]),
            "node 0: its scale does not fit in f32: element 0 (1e39)",
        ),
        (
            |d| d["nodes"][0]["translation"] = json!([0, -1e39, 0]),
            "node 0: its translation does not fit in f32: element 1 (-1e39)",
        ),
        (
            |d| d["nodes"][0]["rotation"] = json!([0, 0, 1e40, 1]),
            "node 0: its rotation does not fit in f32: element 2 (1e40)",
        ),
        (
            |d| {
                let mut m = vec![json!(0); 16];
                m[0] = json!(1);
                m[5] = json!(1);
                m[10] = json!(1);
                m[12] = json!(1e39);
                m[15] = json!(1);
                d["nodes"][0]["matrix"] = Value::Array(m);
            },
            "node 0: its matrix does not fit in f32: element 12 (1e39)",
        ),
        (
            // Nine scales of 1e38, each within f32: 1e342 together, past f64.
            |d| {
                let chain: Vec<Value> = (1..=9).map(|c| json!({"children": [c], "scale": [1e38, 1, 1]})).collect();
                d["nodes"] = Value::Array(chain);
                d["nodes"][8] = json!({"mesh": 0, "scale": [1e38, 1, 1]});
            },
            "node 8: its transform composed with its ancestors' overflows",
        ),
    ];
    for (edit, expected) in cases {
        let mut doc = tiny_gltf();
        edit(&mut doc);
        let e = import_json(dir.path(), "overflow.gltf", &doc).unwrap_err();
        assert!(matches!(&e, ImportError::Gltf { message, .. } if message.starts_with(expected)), "{expected}: {e}");
    }
    // A scale within f32 that makes a vertex too large: the vertex is blamed, as before.
    let mut doc = tiny_gltf();
    doc["nodes"][0]["scale"] = json!([1e20, 1, 1]);
    let e = import_json(dir.path(), "large.gltf", &doc).unwrap_err();
    assert!(matches!(e, ImportError::TooLarge { vertex: 1, .. }), "{e}");
}

/// The bytes of a GLB: the header, then each (type, data) chunk with its header.
fn glb(chunks: &[(&[u8; 4], &[u8])]) -> Vec<u8> {
    let mut body = Vec::new();
    for (ty, data) in chunks {
        body.extend_from_slice(&(data.len() as u32).to_le_bytes());
        body.extend_from_slice(*ty);
        body.extend_from_slice(data);
    }
    let mut bytes = b"glTF\x02\0\0\0".to_vec();
    bytes.extend_from_slice(&(12 + body.len() as u32).to_le_bytes());
    bytes.extend(body);
    bytes
}

/// The one-triangle document of [`tiny_gltf`] as a GLB: its JSON (padded with spaces) and its
/// buffer as the BIN chunk (padded with zeros).
fn tiny_glb() -> Vec<u8> {
    let mut doc = tiny_gltf();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let encoded = uri.split_once(',').unwrap().1;
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    let mut bin = base64_decode(encoded);
    bin.resize(bin.len().next_multiple_of(4), 0);
    let mut json = serde_json::to_vec(&doc).unwrap();
    json.resize(json.len().next_multiple_of(4), b' ');
    glb(&[(b"JSON", &json), (b"BIN\0", &bin)])
}

fn base64_decode(text: &str) -> Vec<u8> {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let sextets: Vec<u32> =
        text.bytes().filter(|&b| b != b'=').map(|b| A.iter().position(|&a| a == b).unwrap() as u32).collect();
    let mut out = Vec::new();
    for group in sextets.chunks(4) {
        let n = group.iter().enumerate().fold(0u32, |n, (k, &s)| n | s << (18 - 6 * k));
        out.extend_from_slice(&n.to_be_bytes()[1..group.len()]);
    }
    out
}

#[test]
fn damaged_glb_containers_are_refused_naming_the_chunk_and_its_offset() {
    let dir = tempfile::tempdir().unwrap();
    let good = tiny_glb();
    let (json, bin) = glb_chunks(&good);
    assert_eq!((json["asset"]["version"].as_str(), bin.len()), (Some("2.0"), 44));
    let path = dir.path().join("tiny.glb");
    std::fs::write(&path, &good).unwrap();
    assert_eq!(import_paths(&[&path]).unwrap().len(), 1);

    let json_len = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let set = |bytes: &mut Vec<u8>, at: usize, value: u32| bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
    let total = good.len();
    type Edit = Box<dyn Fn(&mut Vec<u8>)>;
    let cases: Vec<(Edit, String)> = vec![
        (Box::new(move |b| set(b, 12, 0)), "chunk 0 at byte 12 (JSON) is empty".into()),
        (
            Box::new(move |b| set(b, 12, json_len as u32 + 1)),
            format!("chunk 0 at byte 12 (JSON): its length {} is not a multiple of 4", json_len + 1),
        ),
        (
            Box::new(move |b| set(b, 12, json_len as u32 - 1)),
            format!("chunk 0 at byte 12 (JSON): its length {} is not a multiple of 4", json_len - 1),
        ),
        (
            Box::new(move |b| set(b, 12, 1 << 20)),
            format!("chunk 0 at byte 12 (JSON): its length 1048576 runs past the end of the file ({total} bytes)"),
        ),
        (
            Box::new(|b| b[19] = b'M'),
            "chunk 0 at byte 12 has type 0x4D4F534A (\"JSOM\"), but the first chunk must be JSON (0x4E4F534A)".into(),
        ),
        (
            Box::new(move |b| set(b, bin_at, 48)),
            format!(
                "chunk 1 at byte {bin_at} (BIN): its length 48 runs past the end of the file ({total} bytes) by 4 bytes"
            ),
        ),
        (
            Box::new(move |b| b[bin_at + 4..bin_at + 8].copy_from_slice(b"JSON")),
            format!("chunk 1 at byte {bin_at} is a second JSON chunk"),
        ),
        (
            Box::new(move |b| b[bin_at + 4..bin_at + 8].copy_from_slice(b"BIM\0")),
            format!(
                "buffer 0 is the GLB binary chunk, but the file has none (chunk 1 at byte {bin_at}, of type 0x004D4942"
            ),
        ),
        (
            Box::new(move |b| set(b, 8, 12)),
            format!("its header gives its length as 12 bytes, but the file has {total} ({} bytes after", total - 12),
        ),
        (
            Box::new(move |b| b.extend_from_slice(&[0; 4])),
            format!("its header gives its length as {total} bytes, but the file has {}", total + 4),
        ),
        (
            Box::new(move |b| {
                b.extend_from_slice(&[0; 4]);
                set(b, 8, total as u32 + 4);
            }),
            format!("chunk 2 at byte {total}: only 4 bytes are left, too few for its 8-byte chunk header"),
        ),
        (
            Box::new(move |b| {
                b.extend_from_slice(&[8, 0, 0, 0, b'B', b'I', b'N', 0, 1, 2, 3, 4, 5, 6, 7, 8]);
                set(b, 8, total as u32 + 16);
            }),
            format!("chunk 2 at byte {total} is a BIN chunk, but only chunk 1 (the second) may be BIN"),
        ),
        (
            Box::new(move |b| {
                b.truncate(12);
                set(b, 8, 12);
            }),
            "it ends after its 12-byte header, with no JSON chunk (chunk 0)".into(),
        ),
    ];
    for (edit, expected) in cases {
        let mut bytes = good.clone();
        edit(&mut bytes);
        std::fs::write(&path, &bytes).unwrap();
        let e = import_paths(&[&path]).unwrap_err();
        assert!(matches!(&e, ImportError::Gltf { message, .. } if message.contains(&expected)), "{expected}\n{e}");
    }

    // A chunk of a type glTF does not define, after the others: ignored (as the format
    // requires), with a warning.
    let mut bytes = good.clone();
    bytes.extend_from_slice(&[4, 0, 0, 0, b'X', b'T', b'R', b'A', 1, 2, 3, 4]);
    set(&mut bytes, 8, total as u32 + 12);
    std::fs::write(&path, &bytes).unwrap();
    let scene = import_paths(&[&path]).unwrap();
    assert_eq!(scene.len(), 1);
    let expected =
        format!("GLB chunk 2 at byte {total}, of type 0x41525458 (\"XTRA\") is not a chunk type glTF 2.0 defines");
    assert!(scene.report.warnings.iter().any(|w| w.contains(&expected)), "{:?}", scene.report.warnings);
}

/// The peak resident memory of this process (`VmHWM`), in bytes.
#[cfg(target_os = "linux")]
fn peak_memory() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    line["VmHWM:".len()..].trim().trim_end_matches("kB").trim().parse::<u64>().unwrap() * 1024
}

/// A chain of 300,000 nodes holding one triangle: the import's memory is linear in the nodes and
/// small a node (about 280 bytes, most of it the `gltf` crate's typed document; it was 1,270
/// when the whole document was also kept as a `serde_json::Value` and every node's world
/// transform was kept). Run alone in a child process, so that the peak is this import's.
#[cfg(target_os = "linux")]
#[test]
fn a_deep_node_chain_costs_a_few_hundred_bytes_a_node() {
    const NAME: &str = "a_deep_node_chain_costs_a_few_hundred_bytes_a_node";
    if std::env::var_os("VLF_IMPORT_CHAIN_CHILD").is_none() {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--exact", NAME, "--nocapture", "--test-threads=1"])
            .env("VLF_IMPORT_CHAIN_CHILD", "1")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).contains("1 passed"), "{stderr}");
        return;
    }
    const NODES: usize = 300_000;
    let dir = tempfile::tempdir().unwrap();
    let mut doc = tiny_gltf();
    doc["nodes"] = json!([]);
    let mut text = serde_json::to_string(&doc).unwrap();
    let chain: Vec<String> = (1..NODES).map(|c| format!("{{\"children\":[{c}]}}")).collect();
    let nodes = format!("\"nodes\":[{},{{\"mesh\":0}}]", chain.join(","));
    text = text.replace("\"nodes\":[]", &nodes);
    drop(chain);
    let path = dir.path().join("chain.gltf");
    std::fs::write(&path, &text).unwrap();
    drop(text);
    let before = peak_memory();
    let scene = import_paths(&[&path]).unwrap();
    assert_eq!(scene.len(), 1);
    let per_node = peak_memory().saturating_sub(before) / NODES as u64;
    eprintln!("{per_node} bytes a node");
    assert!(per_node < 600, "{per_node} bytes a node");
}

#[test]
fn node_extensions_are_read_from_the_raw_json() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = tiny_gltf();
    doc["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    doc["nodes"][0]["extensions"] = json!({"EXT_mesh_gpu_instancing": {"attributes": {}}});
    let scene = import_json(dir.path(), "instancing.gltf", &doc).unwrap();
    assert!(
        scene
            .report
            .warnings
            .iter()
            .any(|w| w
                .ends_with("node 0 uses EXT_mesh_gpu_instancing (not supported): only the node itself is imported")),
        "{:?}",
        scene.report.warnings
    );
    // Raw parts of the wrong type: the typed document says what is wrong.
    doc["nodes"][0]["extensions"] = json!(5);
    let e = import_json(dir.path(), "instancing.gltf", &doc).unwrap_err();
    assert!(matches!(&e, ImportError::Gltf { message, .. } if message.contains("invalid type: integer `5`")), "{e}");
}

#[test]
fn a_gltf_whose_first_64_kib_end_inside_a_number_is_read() {
    // The first bytes are judged as a JSON start: one that ends in "1e", "1.", "-" or "tr" is a
    // number or a literal cut short, not a syntax error.
    let dir = tempfile::tempdir().unwrap();
    let rest = serde_json::to_string(&tiny_gltf()).unwrap();
    for (cut, tail) in [("1e", "5"), ("1.", "5"), ("-", "1"), ("tr", "ue"), ("12", "34")] {
        let head = "{\"extras\":{\"pad\":\"";
        let prefix_len = 64 * 1024 + 1;
        let pad = "x".repeat(prefix_len - head.len() - "\",\"n\":".len() - cut.len());
        let text = format!("{head}{pad}\",\"n\":{cut}{tail}}},{}", &rest[1..]);
        assert_eq!(&text[prefix_len - cut.len()..prefix_len], cut);
        let path = dir.path().join("cut.gltf");
        std::fs::write(&path, &text).unwrap();
        let scene = import_paths(&[&path]).unwrap_or_else(|e| panic!("{cut}: {e}"));
        assert_eq!(scene.len(), 1);
    }
}
