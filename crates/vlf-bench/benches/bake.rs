//! The bake's inner loop: one direction of the 100K-triangle scene (rotate, rasterise
//! conservatively, clip to tiles, build the 1D BSPs), reported as triangles per second per
//! direction. `cargo bench -p vlf-bench --bench bake`.

#![forbid(unsafe_code)]

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use vlf_bake::direction::{Limit, Scratch, build_direction};
use vlf_bake::{DepthPolicy, Params, Prepared};
use vlf_bench::experiments::paper_scene;
use vlf_geom::Lattice;
use vlf_geom::frame::frame;

fn one_direction(c: &mut Criterion) {
    let scene = paper_scene(100_000);
    let prep = Prepared::new(&scene);
    let lattice = Lattice::new(16);
    let dirs = lattice.directions();
    let mut g = c.benchmark_group("bake one direction (100K triangles)");
    g.throughput(Throughput::Elements(prep.triangle_count() as u64));
    g.sample_size(20);
    for tiles in [32, 64, 128] {
        let params = Params {
            lattice_n: 16,
            tiles,
            depth: DepthPolicy::default(),
            margin: prep.radius * vlf_bake::params::MARGIN_FRACTION,
        };
        let m = frame(dirs[dirs.len() / 3]);
        let mut scratch = Scratch::default();
        g.bench_function(format!("{tiles}² tiles"), |b| {
            b.iter(|| {
                black_box(build_direction(&prep, &params, &m, 7, &mut scratch, Limit::FORMAT).unwrap().words.len())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, one_direction);
criterion_main!(benches);
