//! Dynamic scenes (`vlf-scene`) against brute force, after every step of random sequences of
//! moves, masks, instance additions and removals, triangle removals (by id and by provenance),
//! insertions and the paper's move (delete, transform, reinsert) of inserted objects.
//!
//! Two references, for every ray:
//! - **Exact** (zero tolerance): for every instance the ray's mask admits, the world ray mapped
//!   into the instance's field exactly as the scene maps it ([`Scene::local_ray`]), tested with
//!   the same f32 kernel against every live triangle of the field (mapped and inserted, removed
//!   ones left out), the least `t` kept. The scene's closest `t` must be bit-identical and its
//!   any-hit answer equal: any difference means the top-level hierarchy, a field or an edit lost
//!   a candidate.
//! - **World**: the same kernel over the current world-space triangles (each live triangle's
//!   vertices mapped by its instance's transform in f64, rounded to f32). The transform moves
//!   rounding: the scene tests an f32 ray rounded in the field's space against the field's f32
//!   vertices, the world brute force an f32 ray against vertices rounded in world space. Each
//!   rounding is a relative 2⁻²⁴ of the magnitudes involved, amplified by the transform's
//!   condition number κ (≤ 6.25 here: scales of 0.4 to 2.5 per axis). The tolerance is therefore
//!   `|Δt|·|d| ≤ 1e-4 · M`, `M` the largest of the origin's, the hit point's and the vertices'
//!   magnitudes (1e-4 ≈ 2¹¹ f32 ulps: κ times 2⁸ ulps for the kernel's own error and the angle
//!   between ray and triangle), or the same triangle with the scene's hit point within
//!   `64·κ·2⁻²⁴·M` of its world plane (a ray nearly parallel to the triangle, where `t` itself is
//!   ill-conditioned). A disagreement where either hit lies within `64·κ·2⁻²⁴·M` of an edge of
//!   its triangle is a float-edge tie, counted apart and not failed; both hitting within the
//!   tolerance on different triangles (instances overlap) is a coincident tie, also counted.

#![forbid(unsafe_code)]

use rayon::prelude::*;
use std::sync::Arc;
use vlf_bake::generate::{self, Rng};
use vlf_bake::scene::{SceneBuilder, SourceDesc};
use vlf_bake::{DepthPolicy, Scene as BakeScene};
use vlf_geom::{BruteForce, Hit, Intersector, Ray};
use vlf_runtime::Field;
use vlf_scene::{Affine, EditError, FieldId, InstanceId, Object, Scene};

/// The transforms' largest condition number (scales 0.4 to 2.5).
const KAPPA: f64 = 6.25;
const EPS: f64 = f32::EPSILON as f64 / 2.0;

/// The fields the scenes place: a cloud of random triangles, and a closed box with a lid and a
/// cloud inside, as three named sources (for removal by provenance).
struct Fields {
    _dirs: Vec<tempfile::TempDir>,
    fields: Vec<Arc<Field>>,
}

fn fields() -> Fields {
    let cloud = BakeScene::from_triangles("cloud", &generate::random_cube(150, 0.2, 3)).unwrap();
    let mut b = SceneBuilder::new();
    let input = b.begin_input("boxed", [0; 32]);
    let walls = b.add_source(input, SourceDesc::program("Walls"));
    let lid = b.add_source(input, SourceDesc::program("Lid"));
    let inner = b.add_source(input, SourceDesc::program("Inner"));
    let bx = generate::closed_box([-1.0, -0.6, -0.4], [1.0, 0.6, 0.4]);
    for (i, t) in bx.iter().enumerate() {
        // The two triangles at z = 0.4 are the lid.
        let source = if t.iter().all(|v| v[2] == 0.4) { lid } else { walls };
        b.push_triangle(source, i as u64, t.map(|v| v.map(f64::from))).unwrap();
    }
    for (i, t) in generate::random_cube(40, 0.1, 8).iter().enumerate() {
        b.push_triangle(inner, i as u64, t.map(|v| [v[0] as f64 * 0.8, v[1] as f64 * 0.5, v[2] as f64 * 0.3])).unwrap();
    }
    let boxed = b.finish().unwrap();
    let mut dirs = Vec::new();
    let mut out = Vec::new();
    for (scene, l, n) in [(&cloud, 19, 12), (&boxed, 33, 8)] {
        let (dir, field) = vlf_tests::bake(scene, l, n, DepthPolicy { leaf_size: 4, max_depth: 6 });
        dirs.push(dir);
        out.push(Arc::new(field));
    }
    Fields { _dirs: dirs, fields: out }
}

/// A random rotation times a random per-axis scale in ±[0.4, 2.5] (mirrored when an odd number
/// of signs is negative), then a translation in the cube of half-side `spread`.
fn random_transform(rng: &mut Rng, spread: f64) -> Affine {
    let q = loop {
        let q = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let n = q.iter().map(|x| x * x).sum::<f64>();
        if n > 1e-3 && n <= 1.0 {
            break q.map(|x| x / n.sqrt());
        }
    };
    let [w, x, y, z] = q;
    let r = [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ];
    let s: [f64; 3] = std::array::from_fn(|_| {
        let m = rng.range(0.4, 2.5);
        if rng.unit() < 0.3 { -m } else { m }
    });
    let t: [f64; 3] = std::array::from_fn(|_| rng.range(-spread, spread));
    Affine::from_3x4(std::array::from_fn(|i| [r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]])).unwrap()
}

/// Counts of one comparison.
#[derive(Default, Debug)]
struct Tally {
    rays: u64,
    hits: u64,
    /// Against the exact reference: closest `t` not bit-identical, or any-hit different.
    mismatches: u64,
    /// Against the world brute force, beyond the tolerance, not at an edge.
    world_mismatches: u64,
    /// Against the world brute force: a hit within float precision of an edge.
    edge_ties: u64,
    /// Both hit within the tolerance, on different triangles.
    coincident: u64,
    /// The largest `|Δt|·|d| / M` among agreeing hits.
    worst: f64,
    examples: Vec<String>,
}

impl Tally {
    fn add(&mut self, o: Tally) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.mismatches += o.mismatches;
        self.world_mismatches += o.world_mismatches;
        self.edge_ties += o.edge_ties;
        self.coincident += o.coincident;
        self.worst = self.worst.max(o.worst);
        self.examples.extend(o.examples.into_iter().take(5usize.saturating_sub(self.examples.len())));
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| a[k] - b[k])
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The world triangles of a scene, live ones only, with the instance and triangle each is.
struct World {
    tris: Vec<[[f32; 3]; 3]>,
    names: Vec<(InstanceId, u32)>,
    masks: Vec<u32>,
}

fn world(scene: &Scene) -> World {
    let mut w = World { tris: Vec::new(), names: Vec::new(), masks: Vec::new() };
    for id in scene.instance_ids() {
        let info = scene.instance(id).unwrap();
        let f = scene.field(info.field).unwrap();
        for prim in 0..f.id_count() {
            if let Some(t) = scene.world_triangle(id, prim) {
                w.tris.push(t.map(|v| v.map(|c| c as f32)));
                w.names.push((id, prim));
                w.masks.push(info.mask);
            }
        }
    }
    w
}

/// A field's live triangles relative to its centre, and their ids.
type Local = (Vec<[[f32; 3]; 3]>, Vec<u32>);

/// Each field's live triangles relative to its centre, with their ids.
fn locals(scene: &Scene) -> Vec<Local> {
    scene
        .fields()
        .iter()
        .map(|f| {
            let ids: Vec<u32> = (0..f.id_count()).filter(|&i| f.triangle_local(i).is_some()).collect();
            (ids.iter().map(|&i| f.triangle_local(i).unwrap()).collect(), ids)
        })
        .collect()
}

/// The exact reference: per admitted instance, the scene's own local ray against every live
/// triangle of its field with the same kernel.
fn exact(scene: &Scene, locals: &[Local], ray: &Ray, mask: u32) -> Option<(Hit, InstanceId)> {
    let mut best: Option<(Hit, InstanceId)> = None;
    for id in scene.instance_ids() {
        let info = scene.instance(id).unwrap();
        if info.mask & mask == 0 {
            continue;
        }
        let local = scene.local_ray(id, ray).unwrap();
        let (tris, ids) = &locals[info.field.0 as usize];
        if let Some(h) = BruteForce::new(tris).closest_hit(&local)
            && best.is_none_or(|(b, _)| h.t < b.t)
        {
            best = Some((Hit { prim: ids[h.prim as usize], ..h }, id));
        }
    }
    best
}

/// The magnitude of a world hit: origin, hit point, vertices.
fn magnitude(ray: &Ray, t: f64, tri: &[[f32; 3]; 3]) -> f64 {
    let p = ray.at(t);
    ray.org
        .iter()
        .map(|&c| (c as f64).abs())
        .chain(p.iter().map(|c| c.abs()))
        .chain(tri.iter().flatten().map(|&c| (c as f64).abs()))
        .fold(0.0, f64::max)
}

fn near_edge(ray: &Ray, t: f64, tri: &[[f32; 3]; 3]) -> bool {
    let (d, limit) = edge_distance(ray, t, tri);
    d <= limit
}

/// The distance from the ray's line to the nearest edge of `tri`, and the distance within which
/// that is a float-edge tie: a ray passing that close to an edge may hit or miss the triangle
/// once the ray or the vertices are rounded in another space. (Measured across the ray, not in
/// the triangle's plane: a ray at a grazing angle moves its hit point far along the plane for a
/// tiny rounding.)
fn edge_distance(ray: &Ray, t: f64, tri: &[[f32; 3]; 3]) -> (f64, f64) {
    let o = ray.org.map(f64::from);
    let d = ray.dir.map(f64::from);
    let dn = d.map(|x| x / norm(d));
    let v = tri.map(|q| q.map(f64::from));
    let dist = (0..3)
        .map(|k| {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let (c, e) = (sub(a, o), sub(b, a));
            let (ce, cd, ed) = (dot(c, e), dot(c, dn), dot(e, dn));
            let qa = dot(e, e) - ed * ed;
            let qb = ce - cd * ed;
            let f = |u: f64| {
                let w: [f64; 3] = std::array::from_fn(|i| c[i] + u * e[i]);
                (dot(w, w) - dot(w, dn).powi(2)).max(0.0).sqrt()
            };
            let u = if qa > 0.0 { (-qb / qa).clamp(0.0, 1.0) } else { 0.0 };
            f(u).min(f(0.0)).min(f(1.0))
        })
        .fold(f64::INFINITY, f64::min);
    (dist, 64.0 * KAPPA * EPS * magnitude(ray, t, tri))
}

fn on_plane(ray: &Ray, t: f64, tri: &[[f32; 3]; 3]) -> bool {
    let p = ray.at(t);
    let v = tri.map(|q| q.map(f64::from));
    let n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
    dot(n, sub(p, v[0])).abs() / norm(n) <= 64.0 * KAPPA * EPS * magnitude(ray, t, tri)
}

fn compare(scene: &Scene, rays: &[(Ray, u32)]) -> Tally {
    let w = world(scene);
    let locals = locals(scene);
    let world_for = |mask: u32| -> (Vec<[[f32; 3]; 3]>, Vec<usize>) {
        let keep: Vec<usize> = (0..w.tris.len()).filter(|&i| w.masks[i] & mask != 0).collect();
        (keep.iter().map(|&i| w.tris[i]).collect(), keep)
    };
    let all = world_for(u32::MAX);
    rays.par_chunks(64)
        .map(|chunk| {
            let mut t = Tally::default();
            for &(ray, mask) in chunk {
                t.rays += 1;
                let got = scene.closest_hit(&ray, mask);
                let got_any = scene.any_hit(&ray, mask);
                let want = exact(scene, &locals, &ray, mask);
                let same = match (got, want) {
                    (None, None) => true,
                    (Some(a), Some((b, _))) => a.hit.t.to_bits() == b.t.to_bits(),
                    _ => false,
                };
                if !same || got_any != want.is_some() {
                    t.mismatches += 1;
                    if t.examples.len() < 5 {
                        t.examples.push(format!(
                            "exact: ray {ray:?} mask {mask:#x}: scene {got:?} any={got_any}, reference {want:?}"
                        ));
                    }
                }
                if got.is_some() {
                    t.hits += 1;
                }
                // The world brute force.
                let owned;
                let (tris, index) = if mask == u32::MAX {
                    (&all.0, &all.1)
                } else {
                    owned = world_for(mask);
                    (&owned.0, &owned.1)
                };
                let wb = BruteForce::new(tris).closest_hit(&ray);
                let wname = wb.map(|h| w.names[index[h.prim as usize]]);
                let dlen = norm(ray.dir.map(f64::from));
                let scene_tri = |h: &vlf_scene::SceneHit| {
                    scene.world_triangle(h.instance, h.hit.prim).expect("a live triangle").map(|v| v.map(|c| c as f32))
                };
                match (got, wb) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        let ta = scene_tri(&a);
                        let tb = &tris[b.prim as usize];
                        let m = magnitude(&ray, b.t as f64, tb).max(magnitude(&ray, a.hit.t as f64, &ta));
                        let dev = (a.hit.t as f64 - b.t as f64).abs() * dlen / m;
                        let same_tri = wname == Some((a.instance, a.hit.prim));
                        if dev <= 1e-4 || (same_tri && on_plane(&ray, a.hit.t as f64, &ta)) {
                            t.worst = t.worst.max(if dev <= 1e-4 { dev } else { 0.0 });
                            if !same_tri {
                                t.coincident += 1;
                            }
                        } else if near_edge(&ray, a.hit.t as f64, &ta) || near_edge(&ray, b.t as f64, tb) {
                            t.edge_ties += 1;
                        } else {
                            t.world_mismatches += 1;
                            if t.examples.len() < 5 {
                                t.examples.push(format!(
                                    "world: ray {ray:?}: scene {a:?}, world {b:?} = {wname:?} (dev {dev:e})"
                                ));
                            }
                        }
                    }
                    (Some(a), None) => {
                        if near_edge(&ray, a.hit.t as f64, &scene_tri(&a)) {
                            t.edge_ties += 1;
                        } else {
                            t.world_mismatches += 1;
                            if t.examples.len() < 5 {
                                t.examples.push(format!(
                                    "world: ray {ray:?} mask {mask:#x}: scene {a:?} (edge distance, limit {:?}), world misses",
                                    edge_distance(&ray, a.hit.t as f64, &scene_tri(&a))
                                ));
                            }
                        }
                    }
                    (None, Some(b)) => {
                        if near_edge(&ray, b.t as f64, &tris[b.prim as usize]) {
                            t.edge_ties += 1;
                        } else {
                            t.world_mismatches += 1;
                            if t.examples.len() < 5 {
                                t.examples.push(format!("world: ray {ray:?}: scene misses, world {b:?} = {wname:?}"));
                            }
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

/// Rays from outside the scene's box aimed into it, from inside it, random lines (some with
/// finite intervals), and rays aimed at vertices, edge midpoints and centroids of live world
/// triangles; a fifth carry a random mask, the rest all bits.
fn rays(scene: &Scene, rng: &mut Rng, per_family: usize) -> Vec<(Ray, u32)> {
    let (lo, hi) = scene.bounds();
    if !(0..3).all(|k| lo[k] <= hi[k]) {
        return Vec::new();
    }
    let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let r = 0.5 * norm(sub(hi, lo));
    let f32s = |v: [f64; 3]| v.map(|x| x as f32);
    let unit = |rng: &mut Rng| loop {
        let v = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let n = norm(v);
        if n > 1e-3 && n <= 1.0 {
            break v.map(|x| x / n);
        }
    };
    let inside = |rng: &mut Rng| -> [f64; 3] { std::array::from_fn(|k| rng.range(lo[k], hi[k])) };
    let w = world(scene);
    let mut out = Vec::new();
    for i in 0..per_family {
        let u = unit(rng);
        let o: [f64; 3] = std::array::from_fn(|k| c[k] + u[k] * r * rng.range(1.1, 3.0));
        out.push(Ray::new(f32s(o), f32s(sub(inside(rng), o))));
        out.push(Ray::new(f32s(inside(rng)), f32s(unit(rng))));
        let o: [f64; 3] = std::array::from_fn(|k| c[k] + rng.range(-1.5, 1.5) * r);
        let d = unit(rng).map(|x| x * rng.range(0.1, 5.0));
        if i % 2 == 0 {
            let tmin = rng.range(0.0, r) as f32;
            out.push(Ray::with_interval(f32s(o), f32s(d), tmin, tmin + rng.range(0.0, 2.0 * r) as f32));
        } else {
            out.push(Ray::new(f32s(o), f32s(d)));
        }
        if !w.tris.is_empty() {
            let t = w.tris[(rng.next_u64() % w.tris.len() as u64) as usize].map(|v| v.map(f64::from));
            let target: [f64; 3] = match rng.next_u64() % 3 {
                0 => t[(rng.next_u64() % 3) as usize],
                1 => std::array::from_fn(|k| 0.5 * (t[0][k] + t[1][k])),
                _ => std::array::from_fn(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0),
            };
            let o = if rng.unit() < 0.5 { inside(rng) } else { std::array::from_fn(|k| c[k] + unit(rng)[k] * 2.0 * r) };
            out.push(Ray::new(f32s(o), f32s(sub(target, o))));
        }
    }
    out.into_iter()
        .map(|ray| (ray, if rng.next_u64().is_multiple_of(5) { rng.next_u64() as u32 } else { u32::MAX }))
        .collect()
}

/// A small random mesh around the origin (in the inserted object's own space).
fn mesh(rng: &mut Rng, count: usize) -> Vec<[[f64; 3]; 3]> {
    generate::random_cube(count, 0.3, rng.next_u64()).iter().map(|t| t.map(|v| v.map(|c| c as f64 * 0.25))).collect()
}

/// A transform placing a mesh made by [`mesh`] well inside a field's bounding sphere.
fn placement(rng: &mut Rng, field: &Field) -> Affine {
    let (c, r) = field.bounding_sphere();
    let a = random_transform(rng, 0.0);
    let rows = a.rows();
    let scale = 0.3 * r / 2.5;
    Affine::from_3x4(std::array::from_fn(|i| {
        [rows[i][0] * scale, rows[i][1] * scale, rows[i][2] * scale, c[i] + rng.range(-0.4, 0.4) * r]
    }))
    .unwrap()
}

/// An inserted object: its field, its mesh, and the ids it has now.
struct Inserted {
    field: FieldId,
    mesh: Vec<[[f64; 3]; 3]>,
    ids: std::ops::Range<u32>,
}

/// Builds a scene of `instances` instances and runs `steps` random steps, comparing after each.
fn run(label: &str, fs: &Fields, instances: usize, steps: usize, per_family: usize, seed: u64) -> Tally {
    let mut rng = Rng::new(seed);
    let spread = 2.0 * (instances as f64).cbrt();
    let mut scene = Scene::new();
    // Fields 0 and 1 shared by many instances; one more of each kept for edits only some see.
    let ids: Vec<FieldId> =
        [0, 1, 0, 1].iter().map(|&k| scene.add_field(vlf_scene::EditedField::new(fs.fields[k].clone()))).collect();
    for _ in 0..instances {
        let f = ids[(rng.next_u64() % ids.len() as u64) as usize];
        let mask = if rng.unit() < 0.2 { 1 << (rng.next_u64() % 32) } else { u32::MAX };
        scene.add_instance(f, random_transform(&mut rng, spread), mask).unwrap();
    }
    scene.rebuild();
    let mut total = compare(&scene, &rays(&scene, &mut rng, per_family));
    let mut inserted: Vec<Inserted> = Vec::new();
    let mut removed_objects = 0;
    for step in 0..steps {
        let live: Vec<InstanceId> = scene.instance_ids().collect();
        let pick = |rng: &mut Rng| live[(rng.next_u64() % live.len().max(1) as u64) as usize];
        // Edits mostly go to a field some instance shows.
        let field = if !live.is_empty() && rng.unit() < 0.75 {
            scene.instance(pick(&mut rng)).unwrap().field
        } else {
            ids[(rng.next_u64() % ids.len() as u64) as usize]
        };
        match rng.next_u64() % 8 {
            // Move a few instances (a tenth of them, at least one).
            0 | 1 if !live.is_empty() => {
                for _ in 0..(live.len() / 10).max(1) {
                    let id = pick(&mut rng);
                    scene.set_transform(id, random_transform(&mut rng, spread)).unwrap();
                }
            }
            2 => {
                if !live.is_empty() && rng.unit() < 0.5 {
                    scene.remove_instance(pick(&mut rng)).unwrap();
                    assert!(scene.set_transform(live.iter().max().copied().unwrap() + 1, Affine::IDENTITY).is_err());
                } else {
                    scene.add_instance(field, random_transform(&mut rng, spread), u32::MAX).unwrap();
                }
            }
            3 if !live.is_empty() => scene.set_mask(pick(&mut rng), 1 << (rng.next_u64() % 32)).unwrap(),
            // Remove a few triangles by id.
            4 => {
                let n = scene.field(field).unwrap().id_count();
                let victims: Vec<u32> = (0..3).map(|_| (rng.next_u64() % n as u64) as u32).collect();
                scene.edit(field, |f| f.remove(&victims)).unwrap().unwrap();
                let bad = scene.edit(field, |f| f.remove(&[n])).unwrap();
                assert!(matches!(bad, Err(EditError::NoSuchTriangle { .. })), "{bad:?}");
            }
            // Remove an object by provenance (fields 1 and 3 have named objects).
            5 => {
                let name = ["Lid", "Inner", "Walls"][removed_objects % 3];
                let r = scene.edit(field, |f| f.remove_object(Object::Name(name))).unwrap();
                if field.0 % 2 == 1 {
                    r.unwrap();
                    removed_objects += 1;
                } else {
                    let e = r.unwrap_err().to_string();
                    assert!(e.contains(name) && e.contains("\"cloud\""), "{e}");
                }
            }
            // Insert an object into a field.
            6 => {
                let count = 1 + (rng.next_u64() % 20) as usize;
                let m = mesh(&mut rng, count);
                let place = placement(&mut rng, &fs.fields[field.0 as usize % 2]);
                let got = scene.edit(field, |f| f.insert(&m, &place)).unwrap().unwrap();
                assert_eq!(got.len(), m.len());
                inserted.push(Inserted { field, mesh: m, ids: got });
            }
            // The paper's move: delete an inserted object, transform it, reinsert it.
            _ => {
                if inserted.is_empty() {
                    continue;
                }
                let k = (rng.next_u64() % inserted.len() as u64) as usize;
                let o = &mut inserted[k];
                let place = placement(&mut rng, &fs.fields[o.field.0 as usize % 2]);
                let ids: Vec<u32> = o.ids.clone().collect();
                let got = scene
                    .edit(o.field, |f| {
                        f.remove(&ids).unwrap();
                        f.insert(&o.mesh, &place)
                    })
                    .unwrap()
                    .unwrap();
                o.ids = got;
            }
        }
        let tally = compare(&scene, &rays(&scene, &mut rng, per_family));
        if tally.mismatches + tally.world_mismatches > 0 {
            panic!("{label}, step {step}: {tally:#?}");
        }
        total.add(tally);
    }
    println!(
        "{label}: {} instances, {steps} steps, {} rays, {} hits, {} mismatches, {} world mismatches, \
         {} float-edge ties, {} coincident ties, worst |Δt|·|d|/M {:.2e}, {} hierarchy rebuilds",
        instances,
        total.rays,
        total.hits,
        total.mismatches,
        total.world_mismatches,
        total.edge_ties,
        total.coincident,
        total.worst,
        scene.rebuilds()
    );
    assert_eq!(total.mismatches, 0, "{label}: {:#?}", total.examples);
    assert_eq!(total.world_mismatches, 0, "{label}: {:#?}", total.examples);
    total
}

#[test]
fn instances_moves_and_edits_equal_brute_force() {
    let fs = fields();
    let mut all = Tally::default();
    for (instances, steps, per_family, seed) in [(1, 30, 60, 1), (10, 30, 40, 2), (100, 20, 25, 3), (1000, 6, 10, 4)] {
        all.add(run(&format!("{instances} instances"), &fs, instances, steps, per_family, seed));
    }
    assert!(all.rays > 10_000 && all.hits > all.rays / 4, "{all:?}");
}

#[test]
#[ignore = "heavy: about a minute on two cores"]
fn many_instances_long_sequences_equal_brute_force() {
    let fs = fields();
    for (instances, steps, per_family, seed) in [(1, 300, 100, 11), (50, 200, 60, 12), (1000, 40, 40, 13)] {
        run(&format!("{instances} instances (long)"), &fs, instances, steps, per_family, seed);
    }
}

#[test]
fn masks_hide_instances_and_t_is_in_world_units() {
    let fs = fields();
    let mut scene = Scene::new();
    let f = scene.add_field(fs.fields[1].clone());
    // The box (half-extents 1, 0.6, 0.4) scaled by 3 along x, mirrored in y, moved to x = 10.
    let t = Affine::from_3x4([[3.0, 0.0, 0.0, 10.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]).unwrap();
    let a = scene.add_instance(f, t, 0b01).unwrap();
    let b = scene.add_instance(f, Affine::translation([30.0, 0.0, 0.0]), 0b10).unwrap();
    // Along -x from x = 0 (with a unit direction): the first instance's wall at x = 10 - 3 = 7.
    let ray = Ray::new([0.0, 0.1, 0.05], [1.0, 0.0, 0.0]);
    let h = scene.closest_hit(&ray, u32::MAX).unwrap();
    assert_eq!(h.instance, a);
    assert!((h.hit.t - 7.0).abs() < 1e-5, "{h:?}");
    // A direction of length 2 halves t.
    let h2 = scene.closest_hit(&Ray::new(ray.org, [2.0, 0.0, 0.0]), u32::MAX).unwrap();
    assert!((h2.hit.t - 3.5).abs() < 1e-5, "{h2:?}");
    // Mask 0b10 sees only the second, at x = 29.
    let h = scene.closest_hit(&ray, 0b10).unwrap();
    assert_eq!(h.instance, b);
    assert!((h.hit.t - 29.0).abs() < 1e-5, "{h:?}");
    assert!(!scene.any_hit(&ray, 0b100));
    // Moving the first instance away uncovers the second without a rebuild of anything but it.
    scene.set_transform(a, Affine::translation([0.0, 50.0, 0.0])).unwrap();
    assert_eq!(scene.closest_hit(&ray, u32::MAX).unwrap().instance, b);
    scene.remove_instance(b).unwrap();
    assert!(scene.closest_hit(&ray, u32::MAX).is_none());
    assert!(scene.remove_instance(b).is_err());
}

/// Many meshes inserted in one call (`insert_all`, what a scene file's inserts use) give the ids,
/// the triangles and the hits that inserting them one call at a time gives; a bad mesh among
/// them is named by its index and nothing is inserted.
#[test]
fn inserting_many_meshes_at_once_equals_one_at_a_time() {
    let fs = fields();
    let base = &fs.fields[0];
    let mut rng = Rng::new(41);
    let meshes: Vec<Vec<[[f64; 3]; 3]>> = (0..12).map(|k| mesh(&mut rng, 1 + k % 5)).collect();
    let places: Vec<Affine> = (0..12).map(|_| placement(&mut rng, base)).collect();
    let mut one = vlf_scene::EditedField::new(base.clone());
    let ranges: Vec<_> = meshes.iter().zip(&places).map(|(m, p)| one.insert(m, p).unwrap()).collect();
    let mut all = vlf_scene::EditedField::new(base.clone());
    let parts: Vec<(&[[[f64; 3]; 3]], &Affine)> = meshes.iter().map(Vec::as_slice).zip(&places).collect();
    assert_eq!(all.insert_all(&parts).unwrap(), ranges);
    assert_eq!(all.inserted_count(), one.inserted_count());
    for id in 0..all.id_count() {
        assert_eq!(all.triangle_local(id), one.triangle_local(id), "triangle {id}");
    }
    let (c, r) = base.bounding_sphere();
    for _ in 0..4000 {
        let o: [f64; 3] = std::array::from_fn(|i| c[i] - base.origin()[i] + rng.range(-r, r));
        let d: [f64; 3] = std::array::from_fn(|_| rng.range(-1.0, 1.0));
        let ray = Ray::new(o.map(|x| x as f32), d.map(|x| x as f32));
        let key = |h: Option<Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()));
        assert_eq!(key(all.closest_hit_local(&ray, &mut ())), key(one.closest_hit_local(&ray, &mut ())), "{ray:?}");
    }
    // A mesh that lands outside the sphere, third of four: named, and nothing inserted.
    let far = Affine::translation([10.0 * r, 0.0, 0.0]);
    let bad: Vec<(&[[[f64; 3]; 3]], &Affine)> = vec![parts[0], parts[1], (meshes[2].as_slice(), &far), parts[3]];
    let before = all.inserted_count();
    let (k, e) = all.insert_all(&bad).unwrap_err();
    assert!(k == 2 && matches!(e, EditError::OutsideSphere { .. }), "{k}: {e}");
    assert_eq!(all.inserted_count(), before);
}

/// Many instances placed in one call (`add_instances`, what a scene file uses) answer as placing
/// them one call at a time does, and the hierarchy is built once, where a grid placed row by row
/// one instance at a time is rebuilt whenever its inner boxes' area doubles; an instance of a
/// field the scene lacks is named by its index and nothing is placed.
#[test]
fn placing_many_instances_at_once_equals_one_at_a_time_and_builds_once() {
    let fs = fields();
    let (_, r) = fs.fields[0].bounding_sphere();
    let (_, r1) = fs.fields[1].bounding_sphere();
    let step = 2.5 * r.max(r1);
    let mut one = Scene::new();
    let mut all = Scene::new();
    let ids: Vec<FieldId> = (0..2).map(|k| one.add_field(fs.fields[k].clone())).collect();
    for k in 0..2 {
        all.add_field(fs.fields[k].clone());
    }
    // A 40 × 40 grid, row by row, every third instance on a mask of its own.
    let spots: Vec<(FieldId, Affine, u32)> = (0..1600)
        .map(|k| {
            let (i, j) = ((k % 40) as f64, (k / 40) as f64);
            let mask = if k % 3 == 0 { 0b10 } else { 0b01 };
            (ids[k % 2], Affine::translation([i * step, j * step, 0.0]), mask)
        })
        .collect();
    for &(f, t, m) in &spots {
        one.add_instance(f, t, m).unwrap();
    }
    assert_eq!(all.add_instances(&spots).unwrap(), 0..1600);
    assert_eq!(all.rebuilds(), 1, "one build for the whole batch");
    println!("1,600 instances row by row, one at a time: {} rebuilds; at once: 1", one.rebuilds());
    let mut rng = Rng::new(77);
    let rays = rays(&all, &mut rng, 400);
    for (ray, mask) in &rays {
        let key = |s: &Scene| s.closest_hit(ray, *mask).map(|f| (f.instance, f.hit.t.to_bits(), f.hit.prim));
        assert_eq!(key(&all), key(&one), "{ray:?} mask {mask:b}");
        assert_eq!(all.any_hit(ray, *mask), one.any_hit(ray, *mask), "{ray:?} mask {mask:b}");
    }
    let tally = compare(&all, &rays);
    assert_eq!(tally.mismatches + tally.world_mismatches, 0, "{tally:#?}");
    // A few more at once go in one by one (no rebuild of the 1,600); a bad field id, third of
    // four, is named and nothing is placed.
    let more: Vec<(FieldId, Affine, u32)> =
        (0..3).map(|k| (ids[1], Affine::translation([k as f64 * step, -step, 0.0]), u32::MAX)).collect();
    assert_eq!(all.add_instances(&more).unwrap(), 1600..1603);
    assert_eq!(all.rebuilds(), 1);
    let bad = [more[0], more[1], (FieldId(7), Affine::IDENTITY, 1), more[2]];
    let (k, e) = all.add_instances(&bad).unwrap_err();
    assert!(k == 2 && e.to_string().contains('7'), "{k}: {e}");
    assert_eq!(all.instance_ids().count(), 1603);
    assert_eq!(all.add_instances(&[]).unwrap(), 1603..1603);
}
