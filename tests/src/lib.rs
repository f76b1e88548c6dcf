//! Test support: the f64 brute-force oracle, ray families, and the comparison that every
//! acceleration path is held to.
//!
//! Two references are used for every ray:
//! - the *same-kernel* brute force ([`vlf_geom::BruteForce`]): every triangle tested with the
//!   runtime's own f32 watertight kernel. The field tests a subset of the triangles with that
//!   same kernel, so its closest `t` must be **bit-identical** and its any-hit answer equal: any
//!   difference means the field lost a candidate. Zero tolerance.
//! - the f64 oracle ([`oracle_closest`]): Möller–Trumbore in f64 on the same f32 vertices. The f32
//!   answer must match it to float precision; where they differ only because the ray grazes an
//!   edge or vertex (the hit point of either answer lies within 16 f32 ulps of the problem's
//!   magnitude from an edge of its triangle), the ray is counted as ambiguous and reported, not
//!   failed.

// Only `CountingAllocator` needs `unsafe` (a global allocator is an unsafe trait).
#![deny(unsafe_code)]

pub mod fuzz;

use rayon::prelude::*;
use std::path::{Path, PathBuf};
use vlf_bake::generate::Rng;
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress, Scene};
use vlf_geom::{BruteForce, Hit, Intersector, Ray};
use vlf_runtime::{Field, InstructionSet, Interleave, TraceStats};

/// The workspace's `fixtures/` directory.
pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures")
}

/// An f64 hit: parameter, triangle, smallest barycentric weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleHit {
    pub t: f64,
    pub prim: u32,
    pub min_bary: f64,
}

/// The ray's origin relative to `origin`, in f64 (exactly as the kernel computes it).
fn local_origin(ray: &Ray, origin: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| ray.org[i] as f64 - origin[i])
}

/// The ray's point at `t`, relative to `origin`, in f64.
fn local_at(ray: &Ray, t: f64, origin: [f64; 3]) -> [f64; 3] {
    let o = local_origin(ray, origin);
    std::array::from_fn(|i| o[i] + t * ray.dir[i] as f64)
}

/// Möller–Trumbore in f64 against one triangle given relative to `origin`, on `[tmin, tmax]`,
/// double-sided.
pub fn oracle_triangle(ray: &Ray, tri: &[[f32; 3]; 3], origin: [f64; 3]) -> Option<(f64, f64)> {
    let o = local_origin(ray, origin);
    let d = ray.dir.map(f64::from);
    let v: [[f64; 3]; 3] = tri.map(|p| p.map(f64::from));
    let e1 = sub(v[1], v[0]);
    let e2 = sub(v[2], v[0]);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = sub(o, v[0]);
    let u = dot(s, p) * inv;
    let q = cross(s, e1);
    let w = dot(d, q) * inv;
    if u < 0.0 || w < 0.0 || u + w > 1.0 {
        return None;
    }
    let t = dot(e2, q) * inv;
    // A hit is reported in f32: one past the largest finite f32 is none (`vlf_geom::T_LIMIT`).
    if t < ray.tmin as f64 || t > (ray.tmax as f64).min(f32::MAX as f64) {
        return None;
    }
    Some((t, u.min(w).min(1.0 - u - w)))
}

/// The closest f64 hit over all triangles (relative to `origin`).
pub fn oracle_closest(ray: &Ray, tris: &[[[f32; 3]; 3]], origin: [f64; 3]) -> Option<OracleHit> {
    if !ray.is_valid() {
        return None;
    }
    let mut best: Option<OracleHit> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some((t, b)) = oracle_triangle(ray, t, origin)
            && best.is_none_or(|h| t < h.t)
        {
            best = Some(OracleHit { t, prim: i as u32, min_bary: b });
        }
    }
    best
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Distance from `p` to the nearest edge of triangle `tri`, in world units.
fn edge_distance(p: [f64; 3], tri: &[[f32; 3]; 3]) -> f64 {
    (0..3)
        .map(|e| {
            let a = tri[e].map(f64::from);
            let b = tri[(e + 1) % 3].map(f64::from);
            let ab = sub(b, a);
            let t = (dot(sub(p, a), ab) / dot(ab, ab).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let q = [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]];
            dot(sub(p, q), sub(p, q)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Largest magnitude among the ray origin, a point and a triangle's vertices (all relative to the
/// triangles' origin).
fn magnitude(ray: &Ray, p: [f64; 3], tri: &[[f32; 3]; 3], origin: [f64; 3]) -> f64 {
    local_origin(ray, origin)
        .iter()
        .map(|c| c.abs())
        .chain(p.iter().map(|c| c.abs()))
        .chain(tri.iter().flatten().map(|c| c.abs() as f64))
        .fold(0.0, f64::max)
}

/// Whether the ray's point at `t` lies within 64 f32 ulps of the problem's magnitude of `tri`'s
/// plane.
fn on_plane(ray: &Ray, t: f64, tri: &[[f32; 3]; 3], origin: [f64; 3]) -> bool {
    let p = local_at(ray, t, origin);
    let v = tri.map(|q| q.map(f64::from));
    let n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
    let dist = dot(n, sub(p, v[0])).abs() / dot(n, n).sqrt();
    dist <= 64.0 * f32::EPSILON as f64 * magnitude(ray, p, tri, origin)
}

/// Whether the hit on triangle `prim` at `t` lies within float precision of that triangle's
/// edges: within 16 f32 ulps of the problem's magnitude (origin, hit point and vertices), where
/// an f32 and an f64 intersector may legitimately disagree.
pub fn grazes(ray: &Ray, t: f64, prim: u32, tris: &[[[f32; 3]; 3]], origin: [f64; 3]) -> bool {
    // A hit at an infinite `t` has no point to measure (every distance there is infinite or NaN,
    // which would pass for grazing): it is no hit at all (`vlf_geom::T_LIMIT`).
    if !t.is_finite() {
        return false;
    }
    let tri = &tris[prim as usize];
    let p = local_at(ray, t, origin);
    edge_distance(p, tri) <= 16.0 * f32::EPSILON as f64 * magnitude(ray, p, tri, origin)
}

/// Counts of one comparison run.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    pub rays: u64,
    pub hits: u64,
    /// Field closest `t` differs from the same-kernel brute force, or any-hit differs.
    pub mismatches: u64,
    /// f32 and f64 disagree beyond float precision on a ray that does not graze an edge.
    pub kernel_mismatches: u64,
    /// f32 and f64 disagree, but the ray grazes an edge or vertex.
    pub ambiguous: u64,
    /// A batch query (interleaved, in turn or automatic) differs from the single-ray query on
    /// the same ray (`t`, `prim`, `u`, `v` bit for bit, or any-hit): counted by [`check_batches`].
    pub batch_mismatches: u64,
    /// The single-ray query run with another instruction set this CPU supports differs
    /// (`t`, `prim`, `u`, `v` bit for bit, the any-hit answer, or the work counted): counted by
    /// [`check_instruction_sets`].
    pub isa_mismatches: u64,
    pub examples: Vec<String>,
}

impl Tally {
    pub fn add(&mut self, o: Tally) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.mismatches += o.mismatches;
        self.kernel_mismatches += o.kernel_mismatches;
        self.ambiguous += o.ambiguous;
        self.batch_mismatches += o.batch_mismatches;
        self.isa_mismatches += o.isa_mismatches;
        self.examples.extend(o.examples.into_iter().take(5usize.saturating_sub(self.examples.len())));
    }
}

/// Compares `accel` with both references on every ray: the brute force over `tris` relative to
/// `origin` (a field's stored triangles and [`Field::origin`]; world triangles and zero for the
/// kd-tree), bit for bit, and the f64 oracle to within float precision.
pub fn compare(accel: &dyn Intersector, tris: &[[[f32; 3]; 3]], origin: [f64; 3], rays: &[Ray]) -> Tally {
    let brute = BruteForce::relative(tris, origin);
    rays.par_chunks(512)
        .map(|chunk| {
            let mut t = Tally::default();
            for ray in chunk {
                t.rays += 1;
                let got = accel.closest_hit(ray);
                let want = brute.closest_hit(ray);
                let got_any = accel.any_hit(ray);
                let want_any = want.is_some();
                let same = match (got, want) {
                    (None, None) => true,
                    (Some(a), Some(b)) => a.t.to_bits() == b.t.to_bits(),
                    _ => false,
                };
                if !same || got_any != want_any {
                    t.mismatches += 1;
                    if t.examples.len() < 5 {
                        t.examples
                            .push(format!("ray {ray:?}: accelerated {got:?} any={got_any}, brute force {want:?}"));
                    }
                }
                if want.is_some() {
                    t.hits += 1;
                }
                let oracle = oracle_closest(ray, tris, origin);
                let agree = match (want, oracle) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        let scale = local_origin(ray, origin).iter().map(|c| c.abs()).fold(1.0, f64::max)
                            / ray.dir.iter().map(|c| c.abs() as f64).fold(0.0, f64::max);
                        (a.t as f64 - b.t).abs() <= 1e-5 * (b.t.abs() + scale)
                            // Same triangle, and the f32 hit point lies on its plane to float
                            // precision: a small backward error where t itself is ill-conditioned
                            // (a ray nearly parallel to the triangle).
                            || (a.prim == b.prim && on_plane(ray, a.t as f64, &tris[a.prim as usize], origin))
                    }
                    _ => false,
                };
                if !agree {
                    let grazing = want.is_some_and(|h| grazes(ray, h.t as f64, h.prim, tris, origin))
                        || oracle.is_some_and(|h| grazes(ray, h.t, h.prim, tris, origin));
                    if grazing {
                        t.ambiguous += 1;
                    } else {
                        t.kernel_mismatches += 1;
                        if t.examples.len() < 5 {
                            t.examples.push(format!("ray {ray:?}: f32 kernel {want:?}, f64 oracle {oracle:?}"));
                        }
                    }
                }
            }
            t
        })
        .reduce(Tally::default, |mut a, b| {
            a.add(b);
            a
        })
}

/// Asserts zero mismatches and reports the counts.
pub fn assert_exact(label: &str, tally: &Tally) {
    println!(
        "{label}: {} rays, {} hits, {} mismatches, {} kernel mismatches, {} ambiguous (grazing), {} batch mismatches, \
         {} instruction-set mismatches",
        tally.rays,
        tally.hits,
        tally.mismatches,
        tally.kernel_mismatches,
        tally.ambiguous,
        tally.batch_mismatches,
        tally.isa_mismatches
    );
    assert_eq!(tally.mismatches, 0, "{label}: field differs from brute force: {:#?}", tally.examples);
    assert_eq!(tally.kernel_mismatches, 0, "{label}: f32 kernel differs from the f64 oracle: {:#?}", tally.examples);
    assert_eq!(tally.batch_mismatches, 0, "{label}: a batch query differs from the single ray: {:#?}", tally.examples);
    assert_eq!(tally.isa_mismatches, 0, "{label}: another instruction set gives another answer: {:#?}", tally.examples);
}

/// Runs `rays` through the field's batch queries in every [`Interleave`] mode and counts, into
/// `tally`, the rays on which one differs from the single-ray query (which [`compare`] holds to
/// the brute force): the closest hit's `t`, `prim`, `u` and `v` bit for bit, and the any-hit
/// answer.
pub fn check_batches(field: &Field, rays: &[Ray], tally: &mut Tally) {
    let view = field.view();
    let key = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
    let single: Vec<_> = rays.iter().map(|r| (key(view.closest_hit(r)), view.any_hit(r))).collect();
    for how in [Interleave::Always, Interleave::Never, Interleave::Auto] {
        let mut closest = vec![None; rays.len()];
        let mut any = vec![false; rays.len()];
        view.closest_hits_in(rays, &mut closest, how);
        view.any_hits_in(rays, &mut any, how);
        for (i, ray) in rays.iter().enumerate() {
            if (key(closest[i]), any[i]) != single[i] {
                tally.batch_mismatches += 1;
                if tally.examples.len() < 5 {
                    tally.examples.push(format!(
                        "ray {ray:?}: batch ({how:?}) {:?} any={}, single ray {:?}",
                        closest[i], any[i], single[i]
                    ));
                }
            }
        }
    }
}

/// Runs `rays` through the single-ray queries with every instruction set this CPU supports
/// ([`vlf_runtime::InstructionSet::supported`]) and counts, into `tally`, the rays on which one
/// differs from the field's default (the widest): the closest hit's `t`, `prim`, `u` and `v` bit
/// for bit, the any-hit answer, and the tiles, leaves and triangle tests counted.
pub fn check_instruction_sets(field: &Field, rays: &[Ray], tally: &mut Tally) {
    let widest = field.view();
    let key = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
    for set in InstructionSet::supported() {
        let view = widest.with_instruction_set(set);
        assert_eq!(view.instruction_set(), set, "{set:?} is supported, so the view uses it");
        for ray in rays {
            let (mut a, mut b) = (TraceStats::default(), TraceStats::default());
            let want = (key(widest.closest_hit_counted(ray, &mut a)), key(widest.any_hit_counted(ray, &mut a)));
            let got = (key(view.closest_hit_counted(ray, &mut b)), key(view.any_hit_counted(ray, &mut b)));
            if got != want || a != b {
                tally.isa_mismatches += 1;
                if tally.examples.len() < 5 {
                    tally.examples.push(format!(
                        "ray {ray:?}: {} gives {got:?} ({b:?}), {} {want:?} ({a:?})",
                        set.name(),
                        widest.instruction_set().name()
                    ));
                }
            }
        }
    }
}

/// Bakes `scene` with explicit parameters into a temporary directory and opens it.
pub fn bake(scene: &Scene, directions: u32, tiles: u32, depth: DepthPolicy) -> (tempfile::TempDir, Field) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("scene.vlf");
    let config = BakeConfig { directions: Some(directions), tiles: Some(tiles), depth, ..BakeConfig::default() };
    vlf_bake::bake_scene(scene, &config, &path, &NoProgress).expect("bake");
    let field = Field::open(&path).expect("open");
    (dir, field)
}

fn unit(rng: &mut Rng) -> [f64; 3] {
    loop {
        let v = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let l2 = dot(v, v);
        if l2 > 1e-6 && l2 <= 1.0 {
            let l = l2.sqrt();
            return [v[0] / l, v[1] / l, v[2] / l];
        }
    }
}

fn in_ball(rng: &mut Rng, c: [f64; 3], r: f64) -> [f64; 3] {
    let u = unit(rng);
    let s = r * rng.unit().cbrt();
    [c[0] + u[0] * s, c[1] + u[1] * s, c[2] + u[2] * s]
}

fn to_f32(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

/// The ray families every scene is tested with, `per_family` rays each: origins inside and
/// outside, random and aimed directions, finite and infinite intervals, rays exactly parallel to
/// stored directions, rays along tile borders, rays aimed exactly at vertices and edge midpoints.
pub fn ray_families(field: &Field, per_family: usize, seed: u64) -> Vec<(&'static str, Vec<Ray>)> {
    let tris: Vec<[[f64; 3]; 3]> =
        (0..field.triangle_count()).map(|i| field.triangle(i).expect("below the count")).collect();
    let mut rng = Rng::new(seed);
    let (c, r) = field.bounding_sphere();
    let reader = field.reader();
    let mut fams: Vec<(&'static str, Vec<Ray>)> = Vec::new();

    let inside: Vec<Ray> =
        (0..per_family).map(|_| Ray::new(to_f32(in_ball(&mut rng, c, r)), to_f32(unit(&mut rng)))).collect();
    fams.push(("inside, random directions", inside));

    let outside: Vec<Ray> = (0..per_family)
        .map(|_| {
            let u = unit(&mut rng);
            let dist = rng.range(1.2, 4.0) * r;
            let o = [c[0] + u[0] * dist, c[1] + u[1] * dist, c[2] + u[2] * dist];
            let target = in_ball(&mut rng, c, r);
            Ray::new(to_f32(o), to_f32(sub(target, o)))
        })
        .collect();
    fams.push(("outside, aimed into the scene", outside));

    let intervals: Vec<Ray> = (0..per_family)
        .map(|_| {
            let o = in_ball(&mut rng, c, 1.5 * r);
            let d = unit(&mut rng);
            let scale = rng.range(0.2, 3.0);
            let tmin = if rng.unit() < 0.5 { 0.0 } else { rng.range(0.0, r) as f32 };
            let tmax = tmin + rng.range(0.0, 2.0 * r) as f32;
            Ray::with_interval(to_f32(o), to_f32([d[0] * scale, d[1] * scale, d[2] * scale]), tmin, tmax)
        })
        .collect();
    fams.push(("finite intervals, unnormalised directions", intervals));

    let l = reader.directions.len();
    let parallel: Vec<Ray> = (0..per_family)
        .map(|_| {
            let j = (rng.next_u64() % l as u64) as usize;
            let w = reader.directions[j];
            let s = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
            Ray::new(to_f32(in_ball(&mut rng, c, 1.2 * r)), [w[0] * s, w[1] * s, w[2] * s])
        })
        .collect();
    fams.push(("exactly parallel to a stored direction", parallel));

    // Lines along tile borders: canonical x or y exactly on a border, back-rotated to world space.
    let n = reader.params.tile_resolution as f64;
    let borders: Vec<Ray> = (0..per_family)
        .map(|_| {
            let j = (rng.next_u64() % l as u64) as usize;
            let m = reader.rotations[j];
            let w = 2.0 * r / n;
            let k = (rng.next_u64() % (n as u64 + 1)) as f64;
            let mut p = [rng.range(-r, r), rng.range(-r, r), -1.5 * r];
            p[(rng.next_u64() % 2) as usize] = -r + k * w;
            // World point: c + Mᵀ p.
            let world = [0, 1, 2].map(|i| c[i] + m[i] * p[0] + m[3 + i] * p[1] + m[6 + i] * p[2]);
            let dir = [m[6], m[7], m[8]];
            // Tilt some by less than a tile across the whole sphere.
            let tilt = if rng.unit() < 0.5 { 0.0 } else { rng.range(-0.5, 0.5) * w / r };
            let d = [dir[0] + tilt * m[0], dir[1] + tilt * m[1], dir[2] + tilt * m[2]];
            Ray::new(to_f32(world), to_f32(d))
        })
        .collect();
    fams.push(("along tile borders", borders));

    let aimed: Vec<Ray> = (0..per_family)
        .map(|_| {
            let t = &tris[(rng.next_u64() % tris.len() as u64) as usize];
            let target: [f64; 3] = match rng.next_u64() % 3 {
                0 => t[(rng.next_u64() % 3) as usize],
                1 => std::array::from_fn(|k| 0.5 * (t[0][k] + t[1][k])),
                _ => std::array::from_fn(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0),
            };
            let o = if rng.unit() < 0.5 { in_ball(&mut rng, c, r) } else { in_ball(&mut rng, c, 3.0 * r) };
            Ray::new(to_f32(o), to_f32(sub(target, o)))
        })
        .collect();
    fams.push(("aimed at vertices, edge midpoints and centroids", aimed));

    // Directions so short that the hits lie at `t` from 10^36 to 10^40, on both sides of the
    // largest finite f32, where a hit is no hit (`vlf_geom::T_LIMIT`): such rays once met two
    // triangles at `t = ∞`, and the farther one won the tie.
    let far: Vec<Ray> = (0..per_family / 4)
        .map(|_| {
            let t = &tris[(rng.next_u64() % tris.len() as u64) as usize];
            let target: [f64; 3] = std::array::from_fn(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0);
            let o = in_ball(&mut rng, c, 3.0 * r);
            let d = sub(target, o);
            let scale = 10f64.powf(-rng.range(36.0, 40.0));
            Ray::new(to_f32(o), to_f32(d.map(|x| x * scale)))
        })
        .filter(Ray::is_valid)
        .collect();
    fams.push(("aimed with tiny directions: hits on both sides of the largest float", far));

    // What a renderer traces after a hit: rays leaving a point on a triangle, to a light (the
    // segment short of both ends, as shadow rays are) or in any direction (a bounce). Any-hit
    // searches walk such a segment from its far end if it leaves the scene, and otherwise put off
    // the leaf it starts in (`vlf-runtime`'s `Setup::for_any_hit`): lights inside and outside
    // the scene's box give both.
    let leaving: Vec<Ray> = (0..per_family)
        .map(|_| {
            let t = &tris[(rng.next_u64() % tris.len() as u64) as usize];
            let (a, b) = (rng.unit(), rng.unit());
            let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
            let o: [f64; 3] = std::array::from_fn(|k| t[0][k] + a * (t[1][k] - t[0][k]) + b * (t[2][k] - t[0][k]));
            if rng.unit() < 0.5 {
                let light = in_ball(&mut rng, c, 3.0 * r);
                Ray::with_interval(to_f32(o), to_f32(sub(light, o)), 1e-4, 1.0 - 1e-4)
            } else {
                let d = unit(&mut rng);
                Ray::with_interval(to_f32(o), to_f32(d), (1e-4 * r) as f32, f32::INFINITY)
            }
        })
        .collect();
    fams.push(("leaving a point on a triangle", leaving));
    fams
}

/// The triangles of a field as stored (relative to [`Field::origin`]).
pub fn stored_triangles(field: &Field) -> Vec<[[f32; 3]; 3]> {
    (0..field.triangle_count()).map(|i| field.triangle_local(i).expect("below the count")).collect()
}

/// Runs every ray family against a field and asserts exactness. `scene` is the scene the field
/// was baked from: its triangles must be the field's.
pub fn check_field(label: &str, field: &Field, scene: &[[[f32; 3]; 3]], per_family: usize, seed: u64) -> Tally {
    let tris = stored_triangles(field);
    assert_eq!(tris, scene, "{label}: the field stores the scene's triangles");
    let mut total = Tally::default();
    for (family, rays) in ray_families(field, per_family, seed) {
        let mut tally = compare(field, &tris, field.origin(), &rays);
        check_batches(field, &rays, &mut tally);
        check_instruction_sets(field, &rays, &mut tally);
        assert_exact(&format!("{label} / {family}"), &tally);
        total.add(tally);
    }
    total
}

/// A global allocator that forwards to the system allocator and counts allocations per thread, so
/// a test can show a stretch of its own code allocates nothing while other tests run in parallel.
/// Install it in a test binary with
/// `#[global_allocator] static GLOBAL: vlf_tests::CountingAllocator = vlf_tests::CountingAllocator;`
/// and read [`allocations_on_this_thread`] before and after.
pub struct CountingAllocator;

thread_local! {
    static THIS_THREAD_ALLOCS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Allocations made so far on the calling thread (through [`CountingAllocator`]).
pub fn allocations_on_this_thread() -> u64 {
    THIS_THREAD_ALLOCS.with(std::cell::Cell::get)
}

// SAFETY: forwards every call to the system allocator unchanged; it only counts them.
#[allow(unsafe_code)]
unsafe impl std::alloc::GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        THIS_THREAD_ALLOCS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as our caller's.
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: same contract as our caller's.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
}
