//! Queries allocate nothing: a counting global allocator sees zero allocations across a frame of
//! closest-hit and any-hit queries, single and batched in every interleaving mode (and `Field` is
//! `Send + Sync`: queried from several threads).

#![forbid(unsafe_code)]

use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_geom::Camera;
use vlf_runtime::Interleave;

#[global_allocator]
static GLOBAL: vlf_tests::CountingAllocator = vlf_tests::CountingAllocator;

#[test]
fn queries_do_not_allocate() {
    let scene = Scene::from_triangles("random", &generate::random_cube(2000, 0.05, 11)).unwrap();
    let (_dir, field) = vlf_tests::bake(&scene, 129, 32, DepthPolicy { leaf_size: 4, max_depth: 8 });
    let (c, r) = field.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(64, 64);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(64, 64));

    let mut closest = vec![None; rays.len()];
    let mut records = vec![vlf_geom::Hit::MISS; rays.len()];
    let mut any = vec![false; rays.len()];
    let before = vlf_tests::allocations_on_this_thread();
    let mut hits = 0u32;
    for ray in &rays {
        hits += field.closest_hit(ray).is_some() as u32;
        hits += field.any_hit(ray) as u32;
    }
    for how in [Interleave::Always, Interleave::Never, Interleave::Auto] {
        field.view().closest_hits_in(&rays, &mut closest, how);
        field.view().any_hits_in(&rays, &mut any, how);
    }
    field.closest_hits(&rays, &mut records);
    field.any_hits(&rays, &mut any);
    let after = vlf_tests::allocations_on_this_thread();
    assert!(hits > 1000, "the frame should hit the scene ({hits})");
    assert_eq!(after - before, 0, "queries allocated");
    // The counter is live: a real allocation on this thread is seen (so zero above means zero).
    let probe: Vec<u64> = std::hint::black_box(Vec::with_capacity(16));
    assert!(vlf_tests::allocations_on_this_thread() > after, "the counting allocator is not installed");
    drop(probe);

    // Shared across threads: the same answers as one thread.
    let expected: Vec<_> = rays.iter().map(|r| field.closest_hit(r)).collect();
    std::thread::scope(|s| {
        for k in 0..4 {
            let (field, rays, expected) = (&field, &rays, &expected);
            s.spawn(move || {
                for (i, ray) in rays.iter().enumerate().skip(k) {
                    assert_eq!(field.closest_hit(ray), expected[i]);
                }
            });
        }
    });
}
