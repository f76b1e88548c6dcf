//! Image tests of the renderer (`crates/vlf-render`): small frames of the fixture room against
//! reference pictures checked into `fixtures/expected/`, and the same frame, bit for bit, from the
//! field, the kd-tree baseline and brute force, from fields baked with different parameters, and
//! on any number of threads.
//!
//! Regenerate the reference pictures with `UPDATE_EXPECT=1 cargo test -p vlf-tests --test render`
//! and look at them before committing.

#![forbid(unsafe_code)]

use std::path::Path;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress, import};
use vlf_geom::BruteForce;
use vlf_geom::Intersector;
use vlf_kdtree::{KdParams, KdTree};
use vlf_render::{Frame, Light, Scene, SceneOptions, Settings, View, default_lights, render};
use vlf_runtime::Field;
use vlf_tests::fixtures;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

fn settings() -> Settings {
    Settings { width: WIDTH, height: HEIGHT, samples: 1, ..Settings::default() }
}

/// Bakes the fixture meshes `inputs` with `directions` × `tiles²` into `dir`.
fn bake(dir: &Path, inputs: &[&str], directions: u32, tiles: u32) -> Field {
    let paths: Vec<_> = inputs.iter().map(|i| fixtures().join("meshes").join(i)).collect();
    let scene = import::import_paths(&paths).unwrap();
    let config = BakeConfig {
        directions: Some(directions),
        tiles: Some(tiles),
        depth: DepthPolicy { leaf_size: 4, max_depth: 6 },
        ..BakeConfig::default()
    };
    let path = dir.join(format!("scene-{directions}-{tiles}.vlf"));
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).unwrap();
    Field::open(&path).unwrap()
}

/// The OBJ room seen through its open side, under the default lights.
fn obj_view() -> View {
    View::look_at([0.0, 12.0, 48.0], [0.0, 12.0, 0.0], [0.0, 1.0, 0.0], 37.8, WIDTH as f64 / HEIGHT as f64)
}

fn frame(tracer: &(impl Intersector + ?Sized), scene: &Scene, view: &View, lights: &[Light]) -> Frame {
    render(tracer, scene, view, lights, &settings(), &|_| {})
}

/// The glTF room through its own camera, under its own lights.
fn gltf_view_and_lights(field: &Field) -> (View, Vec<Light>) {
    let camera = field.cameras().next().expect("the glTF room has a camera");
    let view = View::from_scene_camera(&camera, WIDTH as f64 / HEIGHT as f64).unwrap();
    let lights: Vec<Light> = field.lights().filter_map(|l| Light::from_scene_light(&l)).collect();
    assert_eq!(lights.len(), 2);
    (view, lights)
}

/// Compares 8-bit RGB `actual` with the reference PNG `name`, or rewrites it when UPDATE_EXPECT
/// is set. Floating point and libm may differ a little across machines: every channel may be off
/// by 3, and at most 1% of the pixels by more (a shadow or refraction edge moving by a pixel).
fn expect_image(name: &str, actual: &[u8]) {
    let path = fixtures().join("expected").join(name);
    if std::env::var_os("UPDATE_EXPECT").is_some() {
        std::fs::write(&path, vlf_render::encode_png(WIDTH, HEIGHT, actual).unwrap()).unwrap();
        return;
    }
    let bytes = std::fs::read(&path)
        .unwrap_or_else(|_| panic!("missing {}; run with UPDATE_EXPECT=1 to create it", path.display()));
    let (w, h, expected) = vlf_render::decode_png(&bytes).unwrap();
    assert_eq!((w, h), (WIDTH, HEIGHT), "{name} has another size");
    let mut off = 0;
    let mut worst = 0;
    for (a, e) in actual.chunks_exact(3).zip(expected.chunks_exact(3)) {
        let d = a.iter().zip(e).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        worst = worst.max(d);
        off += (d > 3) as usize;
    }
    let allowed = (WIDTH * HEIGHT) as usize / 100;
    assert!(
        off <= allowed,
        "{name}: {off} pixels differ by more than 3 (at most {allowed} may; the worst by {worst}); if the change is deliberate, rerun with UPDATE_EXPECT=1 and look at the picture"
    );
}

#[test]
fn the_obj_room_matches_its_reference_picture() {
    let dir = tempfile::tempdir().unwrap();
    let field = bake(dir.path(), &["cornell/cornell.obj"], 33, 16);
    let scene = Scene::from_field(&field, &SceneOptions::default());
    let view = obj_view();
    let (center, radius) = field.bounding_sphere();
    let f = frame(&field, &scene, &view, &default_lights(&view, center, radius));
    // The picture exercises every kind of ray: shadows, the mirror block, the glass ball.
    assert!(f.rays.shadow > 0 && f.rays.reflection > 0 && f.rays.refraction > 0, "{:?}", f.rays);
    assert_eq!(f.rays.primary, (WIDTH * HEIGHT) as u64);
    expect_image("cornell-obj-64x48.png", &vlf_render::to_srgb8(&f, 1.0));
}

#[test]
fn the_gltf_room_with_the_bunny_matches_its_reference_picture() {
    let dir = tempfile::tempdir().unwrap();
    let field = bake(dir.path(), &["cornell/cornell.gltf", "bunny.obj"], 33, 16);
    let scene = Scene::from_field(&field, &SceneOptions::default());
    let (view, lights) = gltf_view_and_lights(&field);
    let f = frame(&field, &scene, &view, &lights);
    assert!(f.rays.shadow > 0 && f.rays.reflection > 0 && f.rays.refraction > 0, "{:?}", f.rays);
    expect_image("cornell-gltf-bunny-64x48.png", &vlf_render::to_srgb8(&f, 1.0));
}

/// The field, the kd-tree and brute force share the triangle kernel and return the same hits, so
/// they render the same frame; so do fields baked with other parameters, and any thread count.
#[test]
fn field_kdtree_and_brute_force_render_identical_frames() {
    let dir = tempfile::tempdir().unwrap();
    let field = bake(dir.path(), &["cornell/cornell.obj"], 33, 16);
    let scene = Scene::from_field(&field, &SceneOptions::default());
    let view = obj_view();
    let (center, radius) = field.bounding_sphere();
    let lights = default_lights(&view, center, radius);
    let reference = frame(&field, &scene, &view, &lights);

    // The same triangles in the same frame as the field's (relative to its origin).
    let kdtree = KdTree::build(scene.triangles(), KdParams::default()).relative_to(scene.origin());
    let brute = BruteForce::relative(scene.triangles(), scene.origin());
    let other_field = bake(dir.path(), &["cornell/cornell.obj"], 129, 48);
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let candidates: [(&str, Frame); 4] = [
        ("kd-tree", frame(&kdtree, &scene, &view, &lights)),
        ("brute force", frame(&brute, &scene, &view, &lights)),
        ("a field of 129 directions × 48² tiles", frame(&other_field, &scene, &view, &lights)),
        ("one thread", one_thread.install(|| frame(&field, &scene, &view, &lights))),
    ];
    for (what, f) in candidates {
        let differing = f.color.iter().zip(&reference.color).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{what}: {differing} pixels differ from the field's frame");
        assert_eq!(f.rays, reference.rays, "{what}: other rays were traced");
    }
    // The work differs: that is the point of an acceleration structure.
    let brute_tests = frame(&brute, &scene, &view, &lights).total_work.triangle_tests;
    assert!(reference.total_work.triangle_tests * 10 < brute_tests, "the field tested nearly every triangle");
}

/// The work picture: black where rays missed everything, brightest where the glass ball
/// multiplies the rays, on the scale it reports.
#[test]
fn the_work_picture_shows_where_the_tests_go() {
    let dir = tempfile::tempdir().unwrap();
    let field = bake(dir.path(), &["cornell/cornell.obj"], 33, 16);
    let scene = Scene::from_field(&field, &SceneOptions::default());
    let view = obj_view();
    let (center, radius) = field.bounding_sphere();
    let f = frame(&field, &scene, &view, &default_lights(&view, center, radius));
    let metric = vlf_render::WorkMetric::TriangleTests;
    let image = vlf_render::work_image(&f, metric, None);
    assert_eq!(image.rgb.len(), (WIDTH * HEIGHT * 3) as usize);
    let tests: Vec<u64> = f.work.iter().map(|w| w.triangle_tests).collect();
    assert_eq!(tests.iter().sum::<u64>(), f.total_work.triangle_tests);
    assert_eq!(image.max, *tests.iter().max().unwrap());
    assert!(image.scale_max <= image.max && image.scale_max > 0);
    // The busiest pixel is drawn in the top colour of the scale, an idle one black.
    let busiest = tests.iter().position(|&t| t == image.max).unwrap();
    assert_eq!(image.rgb[3 * busiest..3 * busiest + 3], vlf_render::inferno(1.0));
    if let Some(idle) = tests.iter().position(|&t| t == 0) {
        assert_eq!(image.rgb[3 * idle..3 * idle + 3], vlf_render::inferno(0.0));
    }
    // A fixed scale clips: everything above it is drawn at the top colour.
    let clipped = vlf_render::work_image(&f, metric, Some(1));
    assert_eq!(clipped.scale_max, 1);
    assert!(tests.iter().zip(clipped.rgb.chunks_exact(3)).all(|(&t, c)| (t == 0) || c == vlf_render::inferno(1.0)));
}

/// A floor and a triangle above it, 1 unit across, at `at`: every coordinate a dyadic fraction
/// added to `at`, so the field stores the same local triangles wherever `at` is (exactly).
fn small_scene_at(dir: &Path, name: &str, at: [f64; 3]) -> Field {
    let p = |x: f64, y: f64, z: f64| [at[0] + x, at[1] + y, at[2] + z];
    let triangles = [
        [p(-0.5, 0.0, -0.5), p(0.5, 0.0, 0.5), p(0.5, 0.0, -0.5)],
        [p(-0.5, 0.0, -0.5), p(-0.5, 0.0, 0.5), p(0.5, 0.0, 0.5)],
        [p(-0.25, 0.25, 0.0), p(0.25, 0.25, 0.0), p(0.0, 0.5, 0.125)],
    ];
    let scene = vlf_bake::Scene::from_triangles_f64(name, &triangles).unwrap();
    let config =
        BakeConfig { directions: Some(9), tiles: Some(8), depth: DepthPolicy::default(), ..BakeConfig::default() };
    let path = dir.join(format!("{name}.vlf"));
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).unwrap();
    Field::open(&path).unwrap()
}

/// A scene far from the world's origin (x = 10⁹, where f32 numbers are 64 apart) is drawn as it is
/// at the origin: the renderer traces relative to the field's centre, in f64 until each ray is
/// rounded, so neither the eye nor the hit points nor the lights lose the scene's precision.
/// World-space f32 rays (the renderer before it did so) hit none of it.
#[test]
fn a_small_scene_far_from_the_origin_renders_as_it_does_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let settings = Settings { background: vlf_render::Background::Solid([0.0; 3]), ..settings() };
    let picture = |at: [f64; 3]| {
        let field = small_scene_at(dir.path(), &format!("at-{}", at[0]), at);
        let scene = Scene::from_field(&field, &SceneOptions::default());
        // The camera and the light placed by dyadic offsets too.
        let p = |x: f64, y: f64, z: f64| [at[0] + x, at[1] + y, at[2] + z];
        let view =
            View::look_at(p(0.5, 0.75, 1.0), p(0.0, 0.125, 0.0), [0.0, 1.0, 0.0], 45.0, WIDTH as f64 / HEIGHT as f64);
        let lights = [Light::point(p(0.5, 2.0, 1.0), 4.0)];
        render(&field, &scene, &view, &lights, &settings, &|_| {})
    };
    let near = picture([0.0; 3]);
    let far = picture([1e9, 0.0, 0.0]);
    let drawn = |f: &Frame| f.color.iter().filter(|c| c.iter().any(|&v| v > 0.0)).count();
    let pixels = (WIDTH * HEIGHT) as usize;
    assert!(drawn(&near) > pixels / 4, "the scene at the origin fills {} of {pixels} pixels", drawn(&near));
    assert!(near.rays.shadow > 0, "{:?}", near.rays);
    assert_eq!(drawn(&far), drawn(&near), "pixels drawn at x = 1e9 and at the origin");
    let differing = far.color.iter().zip(&near.color).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels differ between the scene at x = 1e9 and at the origin");
    assert_eq!(far.rays, near.rays);
}

/// The same for a scene of instances (`render --scene`): two instances of the small scene's field
/// moved to x = 10⁹ are drawn as they are at the origin, `Flat` tracing relative to the centre of
/// the scene's content. With world-space f32 rays (`Flat` before it did so) they were not.
#[test]
fn a_scene_of_instances_far_from_the_origin_renders_as_it_does_at_the_origin() {
    let dir = tempfile::tempdir().unwrap();
    let field = std::sync::Arc::new(small_scene_at(dir.path(), "instanced", [0.0; 3]));
    let settings = Settings { background: vlf_render::Background::Solid([0.0; 3]), ..settings() };
    let picture = |x: f64| {
        let mut scene = vlf_scene::Scene::new();
        let f = scene.add_field(field.clone());
        for dx in [0.0, 0.75] {
            scene.add_instance(f, vlf_scene::Affine::translation([x + dx, 0.0, 0.0]), u32::MAX).unwrap();
        }
        let flat = scene.flat().unwrap();
        assert_eq!(flat.origin()[0], x + 0.375, "the centre of the content");
        let shading = Scene::from_instances(&scene, &flat, &SceneOptions::default());
        let p = |a: f64, b: f64, c: f64| [x + a, b, c];
        let view =
            View::look_at(p(0.9, 0.75, 1.5), p(0.375, 0.125, 0.0), [0.0, 1.0, 0.0], 45.0, WIDTH as f64 / HEIGHT as f64);
        let lights = [Light::point(p(0.5, 2.0, 1.0), 4.0)];
        render(&flat, &shading, &view, &lights, &settings, &|_| {})
    };
    let (near, far) = (picture(0.0), picture(1e9));
    let drawn = |f: &Frame| f.color.iter().filter(|c| c.iter().any(|&v| v > 0.0)).count();
    let pixels = (WIDTH * HEIGHT) as usize;
    assert!(drawn(&near) > pixels / 4, "the scene at the origin fills {} of {pixels} pixels", drawn(&near));
    assert!(near.rays.shadow > 0, "{:?}", near.rays);
    assert_eq!(drawn(&far), drawn(&near), "pixels drawn at x = 1e9 and at the origin");
    // The shading scene is made from world triangles (f64, whose steps at 10⁹ are 1.2e-7) made
    // relative to the centre again, so the shading may differ in the last bits; the hits may not.
    let largest = far.color.iter().zip(&near.color).flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()));
    let largest = largest.fold(0.0f32, f32::max);
    assert!(largest < 1e-4, "colours differ by up to {largest} between the scene at x = 1e9 and at the origin");
    assert_eq!(far.rays, near.rays);
}
