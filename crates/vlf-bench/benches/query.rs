//! The parts of a query, each on its own: the constant-time direction lookup, the walk over
//! tiles (a field with one leaf per tile) and over tiles and BSP leaves, the watertight triangle
//! test, and a whole closest-hit query for reference. `cargo bench -p vlf-bench --bench query`.

#![forbid(unsafe_code)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use vlf_bake::generate::Rng;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress};
use vlf_bench::experiments::{paper_scene, views};
use vlf_geom::{Ray, TriRay};
use vlf_runtime::{Field, TraceStats};

fn bake(depth: DepthPolicy) -> (tempfile::TempDir, Field) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.vlf");
    let scene = paper_scene(16_000);
    let config = BakeConfig { directions: Some(2049), tiles: Some(64), depth, ..BakeConfig::default() };
    vlf_bake::bake_scene(&scene, &config, &path, &NoProgress).unwrap();
    let field = Field::open(&path).unwrap();
    (dir, field)
}

fn query_parts(c: &mut Criterion) {
    let (_d1, bsp) = bake(DepthPolicy::default());
    let (_d2, linear) = bake(DepthPolicy { leaf_size: 1, max_depth: 0 });
    let (center, radius) = bsp.bounding_sphere();
    let [(_, outside), (_, inside)] = views(center, radius, 64);
    let rays: Vec<Ray> = outside.into_iter().chain(inside).collect();
    let n = rays.len() as u64;

    let mut g = c.benchmark_group("query parts (16K triangles, 2049 directions × 64²)");
    g.throughput(Throughput::Elements(n));
    let view = bsp.view();
    g.bench_function("direction lookup", |b| {
        b.iter(|| {
            for r in &rays {
                black_box(view.select_direction(r.dir.map(f64::from)));
            }
        })
    });
    // The whole segment inside the sphere, no early exit: walk cost only.
    g.bench_function("tile walk (one leaf per tile)", |b| {
        let v = linear.view();
        b.iter(|| {
            let mut stats = TraceStats::default();
            for r in &rays {
                v.for_each_leaf(r, &mut stats, |ids, _| {
                    black_box(ids);
                    false
                });
            }
            black_box(stats)
        })
    });
    g.bench_function("tile and leaf walk (BSP)", |b| {
        b.iter(|| {
            let mut stats = TraceStats::default();
            for r in &rays {
                view.for_each_leaf(r, &mut stats, |ids, _| {
                    black_box(ids);
                    false
                });
            }
            black_box(stats)
        })
    });
    g.bench_function("closest hit", |b| {
        b.iter(|| {
            for r in &rays {
                black_box(bsp.closest_hit(r));
            }
        })
    });
    g.finish();

    // The kernel alone: one ray against many triangles, a mix of hits and misses.
    let tris = paper_scene(4096).vertices();
    let mut rng = Rng::new(3);
    let ray = Ray::new([rng.range(-0.1, 0.1) as f32, 0.0, 3.0], [0.0, 0.0, -1.0]);
    let tr = TriRay::new(&ray);
    let mut g = c.benchmark_group("triangle test");
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("watertight (Woop et al. 2013, f64)", |b| {
        b.iter(|| {
            for t in &tris {
                black_box(tr.intersect(t[0], t[1], t[2], f32::INFINITY));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, query_parts);
criterion_main!(benches);
