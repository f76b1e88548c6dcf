//! The CRT baseline (`vlf-kdtree`) against the same-kernel brute force (bit for bit) and the f64
//! oracle, over the scene families of `oracle.rs` and several (depth, leaf size) settings, with
//! ray families aimed at a kd-tree's weak spots: rays parallel to axes, lying in splitting planes
//! and grid planes, running along grid lines, with zero direction components and finite
//! intervals. Plus the structure itself: every triangle is in every leaf it overlaps, the build is
//! deterministic, queries allocate nothing.

#![forbid(unsafe_code)]

use vlf_bake::Scene;
use vlf_bake::generate::{self, Rng};
use vlf_geom::{BruteForce, Intersector, Ray};
use vlf_kdtree::{KdParams, KdTree, TraceStats};
use vlf_tests::{Tally, assert_exact, compare};

type Tri = [[f32; 3]; 3];

fn params(max_depth: u32, leaf_size: u32) -> KdParams {
    KdParams { max_depth, leaf_size }
}

// ---------------------------------------------------------------------------------------------
// Ray families

fn unit(rng: &mut Rng) -> [f64; 3] {
    loop {
        let v = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if l2 > 1e-6 && l2 <= 1.0 {
            let l = l2.sqrt();
            return v.map(|c| c / l);
        }
    }
}

fn in_ball(rng: &mut Rng, c: [f64; 3], r: f64) -> [f64; 3] {
    let u = unit(rng);
    let s = r * rng.unit().cbrt();
    std::array::from_fn(|k| c[k] + u[k] * s)
}

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| a[k] - b[k])
}

fn pick(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n as u64) as usize
}

fn coin(rng: &mut Rng) -> bool {
    rng.unit() < 0.5
}

/// A vertex, edge midpoint or centroid of a random triangle.
fn feature(rng: &mut Rng, tris: &[Tri]) -> [f64; 3] {
    let t = &tris[pick(rng, tris.len())];
    match rng.next_u64() % 3 {
        0 => t[pick(rng, 3)].map(f64::from),
        1 => {
            let (a, b) = (pick(rng, 3), pick(rng, 3));
            std::array::from_fn(|k| 0.5 * (t[a][k] as f64 + t[(a + 1 + b % 2) % 3][k] as f64))
        }
        _ => std::array::from_fn(|k| (t[0][k] as f64 + t[1][k] as f64 + t[2][k] as f64) / 3.0),
    }
}

/// An axis-aligned grid scene (`vlf_bake::generate::grid`): spacing, cells per side, layers.
#[derive(Clone, Copy)]
struct Grid {
    scale: f32,
    cells: u32,
    layers: u32,
}

/// The ray families: like `vlf_tests::ray_families`, without a field, plus the kd-tree's
/// special cases (and the grid's, for a grid scene). `per_family` rays each.
fn ray_families(
    tree: &KdTree,
    tris: &[Tri],
    per_family: usize,
    seed: u64,
    grid: Option<Grid>,
) -> Vec<(String, Vec<Ray>)> {
    let mut rng = Rng::new(seed);
    let (lo, hi) = tree.bounds().expect("non-empty scene");
    let (lo, hi) = (lo.map(f64::from), hi.map(f64::from));
    let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let r = 0.5 * sub(hi, lo).iter().map(|e| e * e).sum::<f64>().sqrt();
    let mut fams: Vec<(String, Vec<Ray>)> = Vec::new();
    let mut family = |name: &str, f: &mut dyn FnMut(&mut Rng) -> Ray| {
        let rays = (0..per_family).map(|_| f(&mut rng)).collect();
        fams.push((name.to_string(), rays));
    };

    family("inside, random directions", &mut |rng| Ray::new(f32s(in_ball(rng, c, r)), f32s(unit(rng))));

    family("outside, aimed into the scene", &mut |rng| {
        let u = unit(rng);
        let dist = rng.range(1.2, 4.0) * r;
        let o = std::array::from_fn(|k| c[k] + u[k] * dist);
        Ray::new(f32s(o), f32s(sub(in_ball(rng, c, r), o)))
    });

    family("finite intervals, unnormalised directions, negative tmin", &mut |rng| {
        let o = in_ball(rng, c, 1.5 * r);
        let d = unit(rng);
        let scale = rng.range(0.2, 3.0);
        let tmin = match rng.next_u64() % 3 {
            0 => 0.0,
            1 => rng.range(0.0, r) as f32,
            _ => rng.range(-r, 0.0) as f32,
        };
        let tmax = tmin + rng.range(0.0, 2.0 * r) as f32;
        Ray::with_interval(f32s(o), f32s(d.map(|v| v * scale)), tmin, tmax)
    });

    family("aimed at vertices, edge midpoints and centroids", &mut |rng| {
        let target = feature(rng, tris);
        let o = if coin(rng) { in_ball(rng, c, r) } else { in_ball(rng, c, 3.0 * r) };
        let tmax = if coin(rng) { f32::INFINITY } else { rng.range(0.25, 0.9) as f32 };
        Ray::with_interval(f32s(o), f32s(sub(target, o)), 0.0, tmax)
    });

    family("axis-aligned, some through vertices", &mut |rng| {
        let k = pick(rng, 3);
        let mut o: [f64; 3] = std::array::from_fn(|j| rng.range(lo[j] - 0.2 * r, hi[j] + 0.2 * r));
        if coin(rng) {
            // Through a vertex or edge midpoint: the two other coordinates are its.
            let f = feature(rng, tris);
            o[(k + 1) % 3] = f[(k + 1) % 3];
            o[(k + 2) % 3] = f[(k + 2) % 3];
        }
        let mut d = [0.0f32; 3];
        d[k] = if coin(rng) { 1.0 } else { -rng.range(0.1, 10.0) as f32 };
        Ray::new(f32s(o), d)
    });

    family("one zero direction component, in vertex planes and on the box faces", &mut |rng| {
        let k = pick(rng, 3);
        let mut o = in_ball(rng, c, 1.3 * r);
        o[k] = match rng.next_u64() % 4 {
            0 => feature(rng, tris)[k],
            1 => lo[k],
            2 => hi[k],
            _ => o[k],
        };
        let mut d = unit(rng);
        d[k] = if coin(rng) { 0.0 } else { -0.0 };
        Ray::new(f32s(o), f32s(d))
    });

    // Splitting planes of this tree, at every depth.
    let splits: Vec<(usize, f32)> =
        tree.nodes().iter().filter(|n| !n.is_leaf()).map(|n| (n.axis(), n.split())).take(4096).collect();
    if !splits.is_empty() {
        family("in and across splitting planes", &mut |rng| {
            let (k, s) = splits[pick(rng, splits.len())];
            let mut o = f32s(in_ball(rng, c, 1.2 * r));
            o[k] = s;
            let mut d = f32s(unit(rng));
            match rng.next_u64() % 3 {
                0 => d[k] = 0.0,
                1 => {
                    // Along the intersection line of two splitting planes.
                    let (k2, s2) = splits[pick(rng, splits.len())];
                    if k2 != k {
                        o[k2] = s2;
                        d = [0.0; 3];
                        d[3 - k - k2] = if coin(rng) { 1.0 } else { -1.0 };
                    } else {
                        d[k] = 0.0;
                    }
                }
                _ => {}
            }
            Ray::new(o, d)
        });
    }

    if let Some(g) = grid {
        let s = g.scale as f64;
        let line = |rng: &mut Rng| pick(rng, g.cells as usize + 1) as f64 * s;
        let layer = |rng: &mut Rng| pick(rng, g.layers as usize) as f64 * s;
        let (below, above) = (-s, g.layers as f64 * s);
        family("grid: through grid vertices, perpendicular to the layers", &mut |rng| {
            let (x, y) = (line(rng), line(rng));
            let up = coin(rng);
            let o = [x, y, if up { below } else { above }];
            Ray::new(f32s(o), [0.0, 0.0, if up { 1.0 } else { -1.0 }])
        });
        family("grid: in the plane of a grid line, across the layers", &mut |rng| {
            let k = pick(rng, 2);
            let mut o = [rng.range(-s, (g.cells + 1) as f64 * s), rng.range(-s, (g.cells + 1) as f64 * s), 0.0];
            o[k] = line(rng);
            o[2] = if coin(rng) { below } else { above };
            let target_z = rng.range(0.0, above);
            let mut d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), target_z - o[2]];
            d[k] = 0.0;
            Ray::new(f32s(o), f32s(d))
        });
        family("grid: in a layer's plane, and along its grid lines", &mut |rng| {
            let z = layer(rng);
            if coin(rng) {
                let o = [rng.range(-s, (g.cells + 1) as f64 * s), rng.range(-s, (g.cells + 1) as f64 * s), z];
                let mut d = unit(rng);
                d[2] = 0.0;
                Ray::new(f32s(o), f32s(d))
            } else {
                let k = pick(rng, 2);
                let mut o = [0.0, 0.0, z];
                o[k] = line(rng);
                o[1 - k] = if coin(rng) { -s } else { (g.cells + 1) as f64 * s };
                let mut d = [0.0f32; 3];
                d[1 - k] = if o[1 - k] < 0.0 { 1.0 } else { -1.0 };
                Ray::new(f32s(o), d)
            }
        });
    }
    fams
}

// ---------------------------------------------------------------------------------------------
// Checks

/// Builds one tree per parameter set and holds it to both references on every ray family.
/// Also checks the counted variants agree with the plain ones. Returns the rays traced.
fn run(label: &str, tris: &[Tri], sets: &[KdParams], per_family: usize, seed: u64, grid: Option<Grid>) -> u64 {
    let mut total = Tally::default();
    for (i, &p) in sets.iter().enumerate() {
        let tree = KdTree::build(tris, p);
        check_structure(&tree, tris);
        for (family, rays) in ray_families(&tree, tris, per_family, seed + i as u64, grid) {
            let tally = compare(&tree, tris, [0.0; 3], &rays);
            assert_exact(&format!("{label} ({p:?}) / {family}"), &tally);
            total.add(tally);
            let mut stats = TraceStats::default();
            for ray in rays.iter().step_by(7) {
                let counted = tree.closest_hit_counted(ray, &mut stats);
                assert_eq!(counted, tree.closest_hit(ray), "{ray:?}");
                assert_eq!(tree.any_hit_counted(ray, &mut stats).is_some(), tree.any_hit(ray), "{ray:?}");
            }
            assert!(stats.cells >= stats.leaves && stats.leaves >= stats.rays.min(1), "{stats:?}");
        }
    }
    total.rays
}

/// Size bookkeeping, and conservativeness: a triangle touching a leaf's closed box is referenced
/// by that leaf, and a referenced triangle comes near the leaf's box (so
/// straddling triangles really are clipped, not just boxed).
fn check_structure(tree: &KdTree, tris: &[Tri]) {
    let s = tree.stats();
    let nodes = tree.nodes();
    let inner = nodes.iter().filter(|n| !n.is_leaf()).count() as u64;
    assert_eq!(s.nodes, nodes.len() as u64);
    assert_eq!(s.nodes, 2 * inner + 1);
    assert_eq!(s.leaves, inner + 1);
    assert!(s.empty_leaves <= s.leaves);
    assert!(s.max_depth <= tree.params().max_depth);
    assert_eq!(s.triangles, tris.len() as u64, "every triangle lies in some leaf");
    assert!(s.references >= s.triangles);
    assert!(s.bytes >= 8 * s.nodes + 4 * s.references + 36 * s.triangles);
    if tree.params().max_depth == 0 {
        assert_eq!((s.nodes, s.references), (1, tris.len() as u64));
    }
    let Some((lo, hi)) = tree.bounds() else { return };
    let scale = lo.iter().chain(&hi).map(|v| v.abs() as f64).fold(0.0, f64::max);
    let mut refs = 0u64;
    let mut leaf_boxes = Vec::new();
    let mut work = vec![(0usize, lo.map(f64::from), hi.map(f64::from), 0u32)];
    while let Some((i, lo, hi, depth)) = work.pop() {
        let n = nodes[i];
        if n.is_leaf() {
            refs += n.references().len() as u64;
            leaf_boxes.push((i, lo, hi));
            continue;
        }
        let (k, split) = (n.axis(), n.split() as f64);
        assert!(lo[k] < split && split < hi[k], "split inside the node's box");
        let (mut l_hi, mut h_lo) = (hi, lo);
        l_hi[k] = split;
        h_lo[k] = split;
        work.push((n.first_child(), lo, l_hi, depth + 1));
        work.push((n.first_child() + 1, h_lo, hi, depth + 1));
        assert!(depth < s.max_depth);
    }
    assert_eq!(refs, s.references);
    // Quadratic: only for small scenes.
    if leaf_boxes.len() as u64 * tris.len() as u64 > 20_000_000 {
        return;
    }
    for (i, lo, hi) in leaf_boxes {
        let mut here = vec![false; tris.len()];
        for id in tree.leaf_triangles(i) {
            here[id as usize] = true;
        }
        for (id, t) in tris.iter().enumerate() {
            // Touching counts (the f64 test is exact on the grid's coordinates; elsewhere its
            // rounding is far below the build's margin).
            if !here[id] {
                assert!(!overlaps(t, lo, hi), "triangle {id} touches leaf {i} [{lo:?}, {hi:?}] but is not in it");
            }
            if here[id] {
                let g = 1e-5 * scale;
                assert!(
                    overlaps(t, lo.map(|v| v - g), hi.map(|v| v + g)),
                    "triangle {id} is in leaf {i} but far from it"
                );
            }
        }
    }
}

/// Triangle/box overlap by the separating axis theorem (Akenine-Möller), in f64.
fn overlaps(t: &Tri, lo: [f64; 3], hi: [f64; 3]) -> bool {
    let v: [[f64; 3]; 3] = t.map(|p| p.map(f64::from));
    let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let h: [f64; 3] = std::array::from_fn(|k| 0.5 * (hi[k] - lo[k]));
    let e = [sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    let mut axes = vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], cross(e[0], e[1])];
    for edge in e {
        for k in 0..3 {
            let mut b = [0.0; 3];
            b[k] = 1.0;
            axes.push(cross(edge, b));
        }
    }
    axes.iter().all(|a| {
        let dot = |p: [f64; 3]| (0..3).map(|k| (p[k] - c[k]) * a[k]).sum::<f64>();
        let p = v.map(dot);
        let r: f64 = (0..3).map(|k| h[k] * a[k].abs()).sum();
        let (pmin, pmax) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        pmin <= r && pmax >= -r
    })
}

fn standard_sets() -> Vec<KdParams> {
    vec![params(0, 1), params(8, 4), params(20, 1), params(20, 16)]
}

// ---------------------------------------------------------------------------------------------
// Scene families

#[test]
fn random_triangles_in_a_cube() {
    // Denser than the paper's triangle size, so that most rays hit something.
    let tris = generate::random_cube(1000, 0.15, 1);
    let rays = run("random cube", &tris, &standard_sets(), 4_000, 11, None);
    assert!(rays >= 100_000);
}

#[test]
fn coplanar_grids_with_shared_edges() {
    // Splits of the box [0, 3]² × [0, 0.75] fall on grid lines, grid planes and the layers.
    let grid = Grid { scale: 0.25, cells: 12, layers: 4 };
    let tris = generate::grid(grid.cells, grid.layers, grid.scale);
    run("grid", &tris, &[params(8, 4), params(20, 1), params(20, 16)], 3_000, 21, Some(grid));
}

#[test]
fn long_thin_slivers() {
    let tris = generate::slivers(400, 3);
    run("slivers", &tris, &[params(8, 4), params(20, 1), params(64, 0)], 3_000, 31, None);
}

#[test]
fn degenerate_triangles() {
    let raw = generate::with_degenerates(300, 5);
    let scene = Scene::from_triangles("degenerate", &raw).unwrap();
    assert_eq!(scene.len(), 300);
    let kept = scene.vertices();
    run("degenerate mix", &kept, &[params(8, 4), params(20, 2)], 3_000, 41, None);

    // Kept in the tree, degenerate triangles still answer exactly as the brute force does.
    let brute = BruteForce::new(&raw);
    for p in [params(8, 4), params(20, 1)] {
        let tree = KdTree::build(&raw, p);
        assert_eq!(tree.stats().triangles, raw.len() as u64);
        for (family, rays) in ray_families(&tree, &raw, 1_000, 43, None) {
            for ray in &rays {
                let (got, want) = (tree.closest_hit(ray), brute.closest_hit(ray));
                assert_eq!(got.map(|h| h.t.to_bits()), want.map(|h| h.t.to_bits()), "{family}: {ray:?}");
                assert_eq!(tree.any_hit(ray), brute.any_hit(ray), "{family}: {ray:?}");
            }
        }
    }
}

#[test]
fn the_stanford_bunny_scan() {
    let scene = vlf_bake::import::import_paths(&[vlf_tests::fixtures().join("meshes/bunny.obj")]).expect("bunny");
    let tris = scene.vertices();
    assert_eq!(tris.len(), 3674);
    run("bunny.obj", &tris, &[params(20, 2), params(12, 8)], 2_000, 51, None);
}

#[test]
fn rays_from_inside_a_closed_box_always_hit() {
    let (lo, hi) = ([-1.0f32, -0.5, -0.25], [1.0f32, 0.5, 0.25]);
    let tris = generate::closed_box(lo, hi);
    let brute = BruteForce::new(&tris);
    for p in [params(0, 1), params(20, 1), params(8, 4)] {
        let tree = KdTree::build(&tris, p);
        let mut rng = Rng::new(9);
        let mut misses = 0;
        for i in 0..40_000 {
            let o = [rng.range(-0.9, 0.9) as f32, rng.range(-0.4, 0.4) as f32, rng.range(-0.2, 0.2) as f32];
            // Aim at box edges and corners exactly half the time.
            let target: [f32; 3] = if i % 2 == 0 {
                let mut q: [f32; 3] = std::array::from_fn(|k| if coin(&mut rng) { lo[k] } else { hi[k] });
                let axis = pick(&mut rng, 4);
                if axis < 3 {
                    q[axis] = rng.range(lo[axis] as f64, hi[axis] as f64) as f32;
                }
                q
            } else {
                f32s([rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)])
            };
            let ray = Ray::new(o, std::array::from_fn(|k| target[k] - o[k]));
            match tree.closest_hit(&ray) {
                None => misses += 1,
                Some(h) => assert_eq!(Some(h.t), brute.closest_hit(&ray).map(|h| h.t), "{ray:?}"),
            }
            assert!(tree.any_hit(&ray) || !brute.any_hit(&ray));
        }
        assert_eq!(misses, 0, "rays escaped a closed box ({p:?})");
    }
}

// ---------------------------------------------------------------------------------------------
// The structure itself

#[test]
fn empty_and_tiny_scenes() {
    let empty = KdTree::build(&[], KdParams::default());
    let s = empty.stats();
    assert_eq!((s.nodes, s.leaves, s.references, s.triangles), (1, 1, 0, 0));
    let mut rng = Rng::new(3);
    for _ in 0..1000 {
        let ray = Ray::new(f32s(in_ball(&mut rng, [0.0; 3], 2.0)), f32s(unit(&mut rng)));
        assert_eq!(empty.closest_hit(&ray), None);
        assert!(!empty.any_hit(&ray));
    }
    // One triangle, any parameters; a deep request is clamped.
    let tri = [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]];
    for p in [params(0, 0), params(20, 0), params(1000, 0)] {
        let tree = KdTree::build(&tri, p);
        assert!(tree.params().max_depth <= vlf_kdtree::MAX_DEPTH);
        let hit = tree.closest_hit(&Ray::new([0.25, 0.25, 1.0], [0.0, 0.0, -1.0])).expect("hit");
        assert_eq!((hit.t, hit.prim), (1.0, 0));
        // Invalid rays miss.
        assert_eq!(tree.closest_hit(&Ray::new([0.25, 0.25, 1.0], [0.0; 3])), None);
        assert_eq!(tree.closest_hit(&Ray::with_interval([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], 2.0, 1.0)), None);
        // tmin and tmax are honoured at the hit.
        assert!(tree.any_hit(&Ray::with_interval([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], 1.0, 1.0)));
        assert!(!tree.any_hit(&Ray::with_interval([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], 0.0, 0.99)));
        assert!(!tree.any_hit(&Ray::with_interval([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], 1.01, 5.0)));
    }
}

#[test]
fn build_parameters_shape_the_tree() {
    let tris = generate::random_cube(3000, 0.05, 7);
    let single = KdTree::build(&tris, params(20, 3000));
    assert_eq!(single.stats().nodes, 1, "leaf size ≥ n gives one leaf");
    let flat = KdTree::build(&tris, params(0, 1));
    assert_eq!(flat.stats().nodes, 1, "depth 0 gives one leaf");
    let mut previous = 1;
    for depth in [4, 8, 12, 16] {
        let s = KdTree::build(&tris, params(depth, 2)).stats();
        assert_eq!(s.max_depth, depth, "a dense scene reaches the depth limit");
        assert!(s.nodes > previous);
        previous = s.nodes;
    }
    let coarse = KdTree::build(&tris, params(20, 16)).stats();
    let fine = KdTree::build(&tris, params(20, 1)).stats();
    assert!(coarse.leaves < fine.leaves && coarse.references < fine.references);
}

#[test]
fn build_is_deterministic_across_thread_counts() {
    let tris = generate::random_cube(20_000, 0.05, 5);
    let p = params(20, 2);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| KdTree::build(&tris, p));
    let many = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| KdTree::build(&tris, p));
    assert_eq!(one.nodes(), many.nodes());
    assert_eq!(one.stats(), many.stats());
    let leaves =
        |t: &KdTree| -> Vec<Vec<u32>> { (0..t.nodes().len()).map(|i| t.leaf_triangles(i).collect()).collect() };
    assert_eq!(leaves(&one), leaves(&many));
}

#[test]
fn counted_queries_count() {
    let tris = generate::random_cube(2000, 0.2, 2);
    let tree = KdTree::build(&tris, params(20, 2));
    let mut rng = Rng::new(77);
    let mut stats = TraceStats::default();
    let mut hits = 0;
    for _ in 0..2000 {
        let o = f32s(in_ball(&mut rng, [0.0; 3], 1.0));
        let ray = Ray::new(o, f32s(unit(&mut rng)));
        hits += tree.closest_hit_counted(&ray, &mut stats).is_some() as u64;
    }
    assert_eq!(stats.rays, 2000);
    assert!(hits > 1000);
    assert!(stats.leaves >= hits && stats.cells > stats.leaves && stats.triangle_tests >= hits, "{stats:?}");
    let mut twice = stats;
    twice.add(&stats);
    assert_eq!(twice.triangle_tests, 2 * stats.triangle_tests);
}

#[global_allocator]
static GLOBAL: vlf_tests::CountingAllocator = vlf_tests::CountingAllocator;

#[test]
fn queries_do_not_allocate() {
    let tris = generate::random_cube(5000, 0.05, 3);
    let tree = KdTree::build(&tris, params(24, 1));
    let mut rng = Rng::new(5);
    let rays: Vec<Ray> =
        (0..20_000).map(|_| Ray::new(f32s(in_ball(&mut rng, [0.0; 3], 2.0)), f32s(unit(&mut rng)))).collect();
    let accel: &dyn Intersector = &tree;
    let mut stats = TraceStats::default();
    let before = vlf_tests::allocations_on_this_thread();
    let mut hits = 0u64;
    for ray in &rays {
        hits += accel.closest_hit(ray).is_some() as u64;
        hits += accel.any_hit(ray) as u64;
        hits += tree.closest_hit_counted(ray, &mut stats).is_some() as u64;
    }
    let after = vlf_tests::allocations_on_this_thread();
    assert!(hits > 0);
    assert_eq!(after - before, 0, "queries allocated");
    // The counter is live: a real allocation on this thread is seen (so zero above means zero).
    let probe: Vec<u64> = std::hint::black_box(Vec::with_capacity(16));
    assert!(vlf_tests::allocations_on_this_thread() > after, "the counting allocator is not installed");
    drop(probe);
}
