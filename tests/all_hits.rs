//! The all-hits and hit-count queries against the brute force, over the oracle's scene and ray
//! families (`vlf_tests::ray_families`): every hit list must be the brute force's
//! (`vlf_geom::BruteForce::all_hits`: every triangle through the same kernel, sorted by `t` then
//! id), bit for bit, with and without a per-ray maximum, one ray at a time and in batches on one
//! and on all cores; every count its length; and the first hit the closest-hit query's `t`. Zero
//! mismatches. The f64 oracle (Möller–Trumbore) must find the same triangles, except where a hit
//! grazes an edge or vertex (within float precision of it), which is counted apart.

#![forbid(unsafe_code)]

use rayon::prelude::*;
use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_geom::{BruteForce, Hit, Ray};
use vlf_runtime::{Field, TooManyHits};
use vlf_tests::{bake, grazes, oracle_triangle, ray_families, stored_triangles};

/// The maxima every ray is also asked with (besides none).
const MAXIMA: [usize; 3] = [1, 2, 5];

#[derive(Debug, Default)]
struct Tally {
    rays: u64,
    hits: u64,
    /// Rays with more than one hit.
    multiple: u64,
    /// Any difference from the same-kernel brute force: a list, a truncated list, a count, a batch.
    mismatches: u64,
    /// The f64 oracle hits a triangle the kernel does not (or the other way) away from any edge.
    kernel_mismatches: u64,
    /// The same, where the hit grazes an edge or vertex: float precision decides.
    ambiguous: u64,
    examples: Vec<String>,
}

impl Tally {
    fn add(mut self, o: Tally) -> Tally {
        self.rays += o.rays;
        self.hits += o.hits;
        self.multiple += o.multiple;
        self.mismatches += o.mismatches;
        self.kernel_mismatches += o.kernel_mismatches;
        self.ambiguous += o.ambiguous;
        self.examples.extend(o.examples.into_iter().take(5usize.saturating_sub(self.examples.len())));
        self
    }

    fn fail(&mut self, what: String) {
        self.mismatches += 1;
        if self.examples.len() < 5 {
            self.examples.push(what);
        }
    }
}

/// Bit-for-bit equality of two hit lists (`t`, id and barycentrics).
fn same(a: &[Hit], b: &[Hit]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.prim == y.prim
                && x.t.to_bits() == y.t.to_bits()
                && x.u.to_bits() == y.u.to_bits()
                && x.v.to_bits() == y.v.to_bits()
        })
}

/// Checks one ray; `batch`, `counts` and `firsts` are what the batch calls gave for it.
fn check_ray(field: &Field, brute: &BruteForce<'_>, ray: &Ray, batch: &[Hit], count: u32, firsts: &[Hit]) -> Tally {
    let mut t = Tally { rays: 1, ..Tally::default() };
    let want = brute.all_hits(ray, usize::MAX);
    t.hits += want.len() as u64;
    t.multiple += (want.len() > 1) as u64;
    let got = field.view().all_hits(ray, usize::MAX);
    if !same(&got, &want) {
        t.fail(format!("ray {ray:?}: field {got:?}, brute force {want:?}"));
    }
    if !same(batch, &want) {
        t.fail(format!("ray {ray:?}: parallel batch {batch:?}, brute force {want:?}"));
    }
    if count as usize != want.len() || field.view().hit_count(ray) as usize != want.len() {
        t.fail(format!("ray {ray:?}: count {count}, brute force {} hits", want.len()));
    }
    for k in MAXIMA {
        let got = field.view().all_hits(ray, k);
        if !same(&got, &want[..k.min(want.len())]) {
            t.fail(format!("ray {ray:?}: first {k} {got:?}, brute force {want:?}"));
        }
    }
    if !same(firsts, &want[..1.min(want.len())]) {
        t.fail(format!("ray {ray:?}: batch of firsts {firsts:?}, brute force {want:?}"));
    }
    // The first hit is the closest hit's distance (the closest-hit query may name another
    // triangle at exactly that `t`).
    let closest = field.closest_hit(ray);
    if closest.map(|h| h.t.to_bits()) != want.first().map(|h| h.t.to_bits()) {
        t.fail(format!("ray {ray:?}: closest {closest:?}, first of all {:?}", want.first()));
    }
    // The f64 oracle: the same set of triangles, up to hits that graze an edge.
    let (tris, origin) = (brute.triangles, brute.origin);
    let oracle: Vec<(u32, f64)> = tris
        .iter()
        .enumerate()
        .filter_map(|(i, tri)| oracle_triangle(ray, tri, origin).map(|(t, _)| (i as u32, t)))
        .collect();
    let only_kernel = want.iter().filter(|h| !oracle.iter().any(|o| o.0 == h.prim)).map(|h| (h.prim, h.t as f64));
    let only_oracle = oracle.iter().filter(|o| !want.iter().any(|h| h.prim == o.0)).copied();
    for (prim, at) in only_kernel.chain(only_oracle) {
        if grazes(ray, at, prim, tris, origin) {
            t.ambiguous += 1;
        } else {
            t.kernel_mismatches += 1;
            if t.examples.len() < 5 {
                t.examples.push(format!("ray {ray:?}: triangle {prim} at t = {at}: kernel and f64 oracle disagree"));
            }
        }
    }
    t
}

/// Every ray family against the brute force; returns the tally after asserting exactness.
fn check(label: &str, field: &Field, per_family: usize, seed: u64) -> Tally {
    let tris = stored_triangles(field);
    let brute = BruteForce::relative(&tris, field.origin());
    let mut total = Tally::default();
    for (family, rays) in ray_families(field, per_family, seed) {
        let lists = field.view().par_all_hits_batch(&rays, usize::MAX);
        assert_eq!(
            lists,
            field.view().all_hits_batch(&rays, usize::MAX),
            "{label} / {family}: one core and all differ"
        );
        let firsts = field.view().par_all_hits_batch(&rays, 1);
        let mut counts = vec![0; rays.len()];
        field.view().par_hit_counts(&rays, &mut counts);
        let mut serial = vec![0; rays.len()];
        field.view().hit_counts(&rays, &mut serial);
        assert_eq!(counts, serial, "{label} / {family}: counts on one core and all differ");
        let tally = rays
            .par_iter()
            .enumerate()
            .map(|(i, ray)| check_ray(field, &brute, ray, lists.ray(i), counts[i], firsts.ray(i)))
            .reduce(Tally::default, Tally::add);
        println!(
            "{label} / {family}: {} rays, {} hits ({} rays with several), {} mismatches, {} kernel mismatches, {} ambiguous (grazing)",
            tally.rays, tally.hits, tally.multiple, tally.mismatches, tally.kernel_mismatches, tally.ambiguous
        );
        assert_eq!(tally.mismatches, 0, "{label} / {family}: differs from the brute force: {:#?}", tally.examples);
        assert_eq!(tally.kernel_mismatches, 0, "{label} / {family}: kernel against f64 oracle: {:#?}", tally.examples);
        total = total.add(tally);
    }
    total
}

fn run(label: &str, tris: &[[[f32; 3]; 3]], configs: &[(u32, u32, DepthPolicy)], per_family: usize) -> Tally {
    let scene = Scene::from_triangles(label, tris).expect("scene");
    let mut total = Tally::default();
    for (i, &(l, n, d)) in configs.iter().enumerate() {
        let (_dir, field) = bake(&scene, l, n, d);
        total = total.add(check(&format!("{label} (l={l}, n={n}, {d:?})"), &field, per_family, 41 + i as u64));
    }
    total
}

fn depth(leaf_size: u32, max_depth: u32) -> DepthPolicy {
    DepthPolicy { leaf_size, max_depth }
}

#[test]
fn random_triangles_in_a_cube() {
    let tris = generate::random_cube(1500, 0.08, 3);
    let t = run("random cube", &tris, &[(19, 16, depth(4, 8)), (129, 32, depth(2, 10)), (51, 64, depth(1, 0))], 3000);
    assert!(t.rays >= 50_000 && t.multiple >= 3_000, "too few rays with several hits: {t:?}");
}

#[test]
fn coplanar_grids_where_hits_tie_on_shared_edges() {
    // Integer grids: rays along grid lines hit two triangles at the same `t`, which both count.
    let tris = generate::grid(12, 4, 0.25);
    let t = run("grid", &tris, &[(9, 8, depth(4, 8)), (129, 48, depth(2, 6))], 3000);
    assert!(t.multiple >= 5_000, "{t:?}");
}

#[test]
fn long_thin_slivers() {
    run("slivers", &generate::slivers(800, 5), &[(19, 16, depth(4, 8))], 3000);
}

#[test]
fn the_stanford_bunny_scan() {
    let path = vlf_tests::fixtures().join("meshes/bunny.obj");
    let scene = vlf_bake::import::import_paths(&[path]).expect("bunny imports");
    let (_dir, field) = bake(&scene, 33, 32, depth(4, 8));
    let t = check("bunny.obj", &field, 4000, 7);
    assert!(t.multiple >= 5_000, "{t:?}");
}

#[test]
fn every_ray_from_inside_a_closed_box_counts_a_crossing() {
    // Watertight counts: from inside, every ray hits the box at least once (twice where it passes
    // exactly through an edge the two triangles of a face share: each triangle counts).
    let tris = generate::closed_box([-1.0, -0.5, -0.25], [1.0, 0.5, 0.25]);
    let scene = Scene::from_triangles("box", &tris).unwrap();
    let (_dir, field) = bake(&scene, 51, 16, depth(4, 8));
    let brute_tris = stored_triangles(&field);
    let brute = BruteForce::relative(&brute_tris, field.origin());
    let mut rng = generate::Rng::new(5);
    let rays: Vec<Ray> = (0..20_000)
        .map(|_| {
            let o = [rng.range(-0.9, 0.9) as f32, rng.range(-0.4, 0.4) as f32, rng.range(-0.2, 0.2) as f32];
            let d = [rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32];
            Ray::new(o, d)
        })
        .collect();
    let mut counts = vec![0; rays.len()];
    field.view().par_hit_counts(&rays, &mut counts);
    for (ray, &c) in rays.iter().zip(&counts) {
        assert_eq!(c as usize, brute.all_hits(ray, usize::MAX).len(), "ray {ray:?}");
        assert!(c >= 1, "ray {ray:?} escaped the box");
    }
}

#[test]
fn invalid_rays_and_a_zero_maximum_have_no_hits() {
    let tris = generate::closed_box([-1.0; 3], [1.0; 3]);
    let scene = Scene::from_triangles("box", &tris).unwrap();
    let (_dir, field) = bake(&scene, 9, 4, depth(4, 8));
    let through = Ray::new([0.3, 0.1, 5.0], [0.0, 0.0, -1.0]);
    assert_eq!(field.view().hit_count(&through), 2);
    assert_eq!(field.view().all_hits(&through, usize::MAX).len(), 2);
    assert!(field.view().all_hits(&through, 0).is_empty());
    let hits = field.view().all_hits(&through, usize::MAX);
    assert!(hits[0].t == 4.0 && hits[1].t == 6.0, "{hits:?}");
    for bad in [
        Ray::new([f32::NAN, 0.0, 5.0], [0.0, 0.0, -1.0]),
        Ray::new([0.3, 0.1, 5.0], [0.0, 0.0, 0.0]),
        Ray::new([0.3, 0.1, 5.0], [0.0, f32::INFINITY, -1.0]),
        Ray::with_interval([0.3, 0.1, 5.0], [0.0, 0.0, -1.0], 3.0, 2.0),
        Ray::with_interval([0.3, 0.1, 5.0], [0.0, 0.0, -1.0], f32::NAN, 2.0),
    ] {
        assert_eq!(field.view().hit_count(&bad), 0, "{bad:?}");
        assert!(field.view().all_hits(&bad, usize::MAX).is_empty(), "{bad:?}");
    }
    // A segment that ends between the faces holds the first only; one that starts there, the second.
    assert_eq!(field.view().hit_count(&Ray::with_interval([0.3, 0.1, 5.0], [0.0, 0.0, -1.0], 0.0, 5.0)), 1);
    let later = field.view().all_hits(&Ray::with_interval([0.3, 0.1, 5.0], [0.0, 0.0, -1.0], 5.0, f32::INFINITY), 9);
    assert_eq!(later.iter().map(|h| h.t).collect::<Vec<_>>(), [6.0]);
    let batch = field.view().all_hits_batch(&[], 3);
    assert_eq!((batch.offsets.as_slice(), batch.len()), (&[0u64][..], 0));
}

#[test]
fn a_batch_stops_at_its_limit_on_hits_and_returns_the_same_lists_within_it() {
    // Rays from above a box, most through two of its faces, some past it: the batch's total is
    // known only by tracing it, and the limit must stop it there on one core and on all.
    let tris = generate::closed_box([-1.0; 3], [1.0; 3]);
    let scene = Scene::from_triangles("box", &tris).unwrap();
    let (_dir, field) = bake(&scene, 9, 4, depth(4, 8));
    let mut rng = generate::Rng::new(8);
    let rays: Vec<Ray> = (0..5_000)
        .map(|_| {
            let o = [rng.range(-1.2, 1.2) as f32, rng.range(-1.2, 1.2) as f32, 5.0];
            Ray::new(o, [rng.range(-0.3, 0.3) as f32, rng.range(-0.3, 0.3) as f32, -1.0])
        })
        .collect();
    let view = field.view();
    let all = view.all_hits_batch(&rays, usize::MAX);
    let total = all.hits.len();
    assert!(total > 3_000, "most rays should hit the box: {total} hits");
    assert_eq!(view.all_hits_batch_within(&rays, usize::MAX, total), Ok(all.clone()));
    assert_eq!(view.par_all_hits_batch_within(&rays, usize::MAX, total), Ok(all.clone()));
    let fewer = TooManyHits { limit: total - 1 };
    assert_eq!(view.all_hits_batch_within(&rays, usize::MAX, total - 1), Err(fewer));
    assert_eq!(view.par_all_hits_batch_within(&rays, usize::MAX, total - 1), Err(fewer));
    assert_eq!(
        view.par_all_hits_batch_within(&rays, usize::MAX, 0).unwrap_err().to_string(),
        "the rays have more than 0 hits in all"
    );
    // With a maximum per ray, the limit counts what is returned.
    let firsts = view.all_hits_batch(&rays, 1);
    assert_eq!(view.par_all_hits_batch_within(&rays, 1, firsts.hits.len()), Ok(firsts));
}
