//! Queries allocate nothing: a counting global allocator sees zero allocations across a frame of
//! closest-hit and any-hit queries (and `Field` is `Send + Sync`: queried from several threads).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};
use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_geom::Camera;

struct Counting;
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

// SAFETY: forwards to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as our caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as our caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn queries_do_not_allocate() {
    let scene = Scene::from_triangles("random", &generate::random_cube(2000, 0.05, 11)).unwrap();
    let (_dir, field) = vlf_tests::bake(&scene, 129, 32, DepthPolicy { leaf_size: 4, max_depth: 8 });
    let (c, r) = field.bounding_sphere();
    let mut rays = Camera::outside(c, r, 1.0).primary_rays(64, 64);
    rays.extend(Camera::inside(c, r, 1.0).primary_rays(64, 64));

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut hits = 0u32;
    for ray in &rays {
        hits += field.closest_hit(ray).is_some() as u32;
        hits += field.any_hit(ray) as u32;
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(hits > 1000, "the frame should hit the scene ({hits})");
    assert_eq!(after - before, 0, "queries allocated");

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
