//! Every acceleration path against the brute-force oracle, over many scene families and ray
//! families (see `vlf_tests` for what "exact" means). Over a million rays in all.

#![forbid(unsafe_code)]

use vlf_bake::generate;
use vlf_bake::{DepthPolicy, Scene};
use vlf_tests::{bake, check_field};

fn depth(leaf_size: u32, max_depth: u32) -> DepthPolicy {
    DepthPolicy { leaf_size, max_depth }
}

fn run(label: &str, tris: &[[[f32; 3]; 3]], configs: &[(u32, u32, DepthPolicy)], per_family: usize) -> u64 {
    let scene = Scene::from_triangles(label, tris).expect("scene");
    let kept = scene.vertices();
    let mut rays = 0;
    for (i, &(l, n, d)) in configs.iter().enumerate() {
        let (_dir, field) = bake(&scene, l, n, d);
        rays += check_field(&format!("{label} (l={l}, n={n}, {d:?})"), &field, &kept, per_family, 17 + i as u64).rays;
    }
    rays
}

#[test]
fn random_triangles_in_a_cube() {
    // The paper's scene family, at coarse and fine resolutions, with and without BSP; 513
    // directions (16 segments) choose their direction without the runtime's fine table; 33 × 128²
    // places its leaves at the fine grids' leaf cost (`vlf_raster::leaves::leaf_cost`).
    let tris = generate::random_cube(1500, 0.08, 1);
    let rays = run(
        "random cube",
        &tris,
        &[
            (3, 4, depth(4, 8)),
            (19, 16, depth(4, 8)),
            (129, 32, depth(2, 10)),
            (51, 64, depth(1, 0)),
            (513, 8, depth(4, 8)),
            (33, 128, depth(4, 8)),
        ],
        12_000,
    );
    assert!(rays >= 420_000);
}

#[test]
fn coplanar_grids_with_shared_edges() {
    // Integer grids: rays exactly in the planes, along grid lines and through shared vertices.
    let tris = generate::grid(12, 4, 0.25);
    run("grid", &tris, &[(9, 8, depth(4, 8)), (129, 48, depth(2, 6))], 12_000);
}

#[test]
fn long_thin_slivers() {
    let tris = generate::slivers(800, 3);
    run("slivers", &tris, &[(19, 16, depth(4, 8)), (129, 64, depth(4, 8))], 12_000);
}

#[test]
fn scenes_far_from_the_origin() {
    // Issue 11: the paper's random triangles, 0.1 across, centred at 1e5, 1e6 and 1e7. They are
    // imported in f64 and stored relative to the scene's centre, so none collapses; rays (f32 in
    // the world, as callers give them) are checked against the brute force over the same stored
    // triangles.
    for (i, centre) in [1e5, 3e6, 1e7].into_iter().enumerate() {
        let local = generate::random_cube(1000, 0.05, 40 + i as u64);
        let far: Vec<[[f64; 3]; 3]> = local
            .iter()
            .map(|t| t.map(|v| [v[0] as f64 + centre, v[1] as f64 - centre, v[2] as f64 + 0.5 * centre]))
            .collect();
        let scene = Scene::from_triangles_f64("far", &far).expect("scene");
        assert_eq!(scene.len(), 1000, "centre {centre}: no triangle is lost");
        assert_eq!((scene.report.dropped_degenerate, scene.report.dropped_precision), (0, 0));
        let kept = scene.vertices();
        for (k, &(l, n, d)) in [(19, 16, depth(4, 8)), (33, 64, depth(4, 8))].iter().enumerate() {
            let (_dir, field) = bake(&scene, l, n, d);
            let o = field.origin();
            assert!((o[0] - centre).abs() < 2.0 && (o[1] + centre).abs() < 2.0, "centre {centre}: origin {o:?}");
            check_field(&format!("far, centre {centre:e} (l={l}, n={n})"), &field, &kept, 6_000, 50 + k as u64);
        }
    }
}

#[test]
fn duplicated_and_coincident_triangles() {
    // Issue 11: exact duplicates and the same corners in another order (merged at import, their
    // provenance kept), and coincident triangles that are not duplicates (in the same plane and
    // overlapping: shrunk towards the centroid, or slid along an edge), which the field must
    // answer like the brute force: the lowest id wins a tie at equal t.
    let base = generate::random_cube(300, 0.1, 61);
    let mut tris = Vec::new();
    for (i, t) in base.iter().enumerate() {
        tris.push(*t);
        let c = [0, 1, 2].map(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0);
        let edge = [0, 1, 2].map(|k| t[1][k] - t[0][k]);
        tris.push(match i % 4 {
            0 => *t,                                                       // an exact duplicate
            1 => [t[2], t[0], t[1]],                                       // the same corners
            2 => t.map(|v| [0, 1, 2].map(|k| c[k] + 0.6 * (v[k] - c[k]))), // shrunk, same plane
            _ => t.map(|v| [0, 1, 2].map(|k| v[k] + 0.3 * edge[k])),       // slid along an edge
        });
    }
    let scene = Scene::from_triangles("coincident", &tris).expect("scene");
    assert_eq!(scene.report.dropped_duplicates, 150, "every copy of the same corners is merged");
    assert_eq!(scene.len(), 450);
    run("coincident", &tris, &[(9, 8, depth(4, 8)), (33, 32, depth(2, 12)), (19, 64, depth(1, 0))], 8_000);
}

#[test]
fn degenerate_triangles_are_dropped_and_the_rest_is_exact() {
    let tris = generate::with_degenerates(600, 5);
    let scene = Scene::from_triangles("degenerate", &tris).unwrap();
    assert_eq!(scene.report.dropped_degenerate, 600);
    assert_eq!(scene.len(), 600);
    run("degenerate mix", &tris, &[(33, 24, depth(4, 8))], 12_000);
}

#[test]
fn rays_from_inside_a_closed_box_always_hit() {
    // Watertightness end to end: from inside a closed mesh every ray must hit, through edges
    // and corners included.
    let tris = generate::closed_box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.25]);
    let scene = Scene::from_triangles("box", &tris).unwrap();
    let (_dir, field) = bake(&scene, 51, 16, depth(4, 8));
    let mut rng = generate::Rng::new(9);
    let mut misses = 0;
    for i in 0..100_000 {
        let o = [rng.range(-0.9, 0.9) as f32, rng.range(-0.4, 0.4) as f32, rng.range(-0.2, 0.2) as f32];
        // Aim at box edges and corners exactly half the time.
        let target: [f32; 3] = if i % 2 == 0 {
            let corner = |s: f64, lo: f32, hi: f32| if s < 0.5 { lo } else { hi };
            let mut p = [corner(rng.unit(), -1.0, 1.0), corner(rng.unit(), -0.5, 0.5), corner(rng.unit(), -0.25, 0.25)];
            let axis = (rng.next_u64() % 4) as usize;
            if axis < 3 {
                let (lo, hi) = [(-1.0, 1.0), (-0.5, 0.5), (-0.25, 0.25)][axis];
                p[axis] = rng.range(lo, hi) as f32;
            }
            p
        } else {
            [rng.range(-2.0, 2.0) as f32, rng.range(-2.0, 2.0) as f32, rng.range(-2.0, 2.0) as f32]
        };
        let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        if field.closest_hit(&vlf_geom::Ray::new(o, d)).is_none() {
            misses += 1;
        }
    }
    assert_eq!(misses, 0, "rays escaped a closed box");
}

/// Imports a fixture mesh as the CLI would.
fn fixture_scene(name: &str) -> Scene {
    vlf_bake::import::import_paths(&[vlf_tests::fixtures().join("meshes").join(name)]).expect("fixture imports")
}

fn run_scene(label: &str, scene: &Scene, configs: &[(u32, u32, DepthPolicy)], per_family: usize) -> u64 {
    let kept = scene.vertices();
    let mut rays = 0;
    for (i, &(l, n, d)) in configs.iter().enumerate() {
        let (_dir, field) = bake(scene, l, n, d);
        rays += check_field(&format!("{label} (l={l}, n={n}, {d:?})"), &field, &kept, per_family, 91 + i as u64).rays;
    }
    rays
}

#[test]
fn the_stanford_bunny_scan() {
    let scene = fixture_scene("bunny.obj");
    assert_eq!(scene.len(), 3674);
    run_scene("bunny.obj", &scene, &[(33, 32, depth(4, 8)), (513, 64, depth(4, 8))], 20_000);
}

#[test]
fn a_gltf_scene_with_node_transforms() {
    // Two bunny instances under rotation, scale and translation, plus a ground quad.
    let scene = fixture_scene("bunny_scene.glb");
    assert_eq!(scene.len(), 7350);
    run_scene("bunny_scene.glb", &scene, &[(129, 48, depth(4, 8))], 16_000);
    let boxed = fixture_scene("Box.gltf");
    run_scene("Box.gltf", &boxed, &[(19, 8, depth(1, 4))], 8_000);
}
