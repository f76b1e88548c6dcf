//! `vlf-bench dynamic` (issue 13): dynamic scenes of baked fields (`vlf_scene`) on this machine.
//!
//! 1. **Instances**: `instances` placements of one `mesh_triangles`-triangle field under random
//!    rotations, per-axis scales of 0.5 to 1.5 with random signs (mirroring) and translations;
//!    primary rays of a camera framing them and incoherent rays (origins uniform in their box,
//!    directions uniform), closest and any hit, against Embree's two-level instancing (one BVH over
//!    the mesh, instanced, with the `embree` feature) on the same rays in the same run.
//! 2. **Updates**: `updates` instance transforms changed per frame, over `frames` frames: the
//!    scene's refit against Embree's top-level rebuild (`rtcCommitScene`); then the incoherent
//!    rays again, to show what the refits cost the queries.
//! 3. **Edits**: the paper's delete and reinsert of an object of each of `objects` triangles in a
//!    `big_triangles` field (a move: the object deleted, turned, and inserted again), the first
//!    move (from the mapped bytes) and the following ones (from the in-memory overlay), and
//!    closest-hit speed as moves accumulate; with Embree, its full rebuild of the same mesh.
//!
//! Rays are traced on all threads of rayon's pool (`--threads`), both contestants alike; every
//! time is the median of `repeats` runs after a warm-up run.

#[cfg(feature = "embree")]
#[allow(unsafe_code)] // The FFI to Embree's C shim: every unsafe block says why it is sound.
pub mod embree;

use crate::median;
use anyhow::{Context, Result};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use vlf_bake::generate::{self, Rng};
use vlf_bake::scene::{SceneBuilder, SourceDesc};
use vlf_bake::{BakeConfig, NoProgress, Scene as BakeScene};
use vlf_geom::{Camera, Ray};
use vlf_runtime::Field;
use vlf_scene::{Affine, EditedField, Object, Scene};

/// What to run.
#[derive(Clone, Debug)]
pub struct DynamicConfig {
    /// Where fields are baked (deleted after use).
    pub work: PathBuf,
    /// Timed runs per measurement, after a warm-up run.
    pub repeats: usize,
    /// Instances of the instanced field.
    pub instances: u32,
    /// Triangles of the instanced field.
    pub mesh_triangles: usize,
    /// Width and height of the primary rays' image.
    pub resolution: u32,
    /// Incoherent rays.
    pub incoherent: usize,
    /// Instances moved per frame.
    pub updates: u32,
    /// Frames of updates.
    pub frames: usize,
    /// Triangles of the edited field.
    pub big_triangles: usize,
    /// Triangles of each moved object.
    pub objects: Vec<usize>,
    /// Moves of each object.
    pub moves: usize,
    /// Directions and tiles of the edited field (the instanced one is baked automatically).
    pub big_params: (u32, u32),
    /// The command line, for the report.
    pub command: String,
    /// Progress lines on standard error.
    pub verbose: bool,
}

fn say(c: &DynamicConfig, s: &str) {
    if c.verbose {
        eprintln!("dynamic: {s}");
    }
}

/// The median seconds of `repeats` runs of `f` after one warm-up run.
fn timed(repeats: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut runs: Vec<f64> = (0..repeats.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    median(&mut runs)
}

/// Millions of rays per second for `n` rays in `seconds`.
fn mrays(n: usize, seconds: f64) -> f64 {
    n as f64 / seconds / 1e6
}

/// A random rotation times per-axis scales of ±[0.5, 1.5], then a translation in `[-spread, spread]³`.
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
    let s: [f64; 3] = std::array::from_fn(|_| rng.range(0.5, 1.5) * if rng.unit() < 0.25 { -1.0 } else { 1.0 });
    let t: [f64; 3] = std::array::from_fn(|_| rng.range(-spread, spread));
    Affine::from_3x4(std::array::from_fn(|i| [r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]]))
        .expect("a rotation times a non-zero scale")
}

/// Incoherent rays: origins uniform in the box, directions uniform on the sphere.
fn incoherent(lo: [f64; 3], hi: [f64; 3], count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            let o: [f64; 3] = std::array::from_fn(|k| rng.range(lo[k], hi[k]));
            let d = loop {
                let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
                let n = d.iter().map(|x| x * x).sum::<f64>();
                if n > 1e-6 && n <= 1.0 {
                    break d;
                }
            };
            Ray::new(o.map(|v| v as f32), d.map(|v| v as f32))
        })
        .collect()
}

/// Bakes `scene` into `work/name` with `directions × tiles` (0: automatic) and opens it.
fn bake(c: &DynamicConfig, scene: &BakeScene, name: &str, params: (u32, u32)) -> Result<(PathBuf, Field)> {
    std::fs::create_dir_all(&c.work)?;
    let path = c.work.join(name);
    let config = BakeConfig {
        directions: (params.0 > 0).then_some(params.0),
        tiles: (params.1 > 0).then_some(params.1),
        ..BakeConfig::default()
    };
    let start = Instant::now();
    vlf_bake::bake_scene(scene, &config, &path, &NoProgress).with_context(|| format!("bake {}", path.display()))?;
    let field = Field::open(&path)?;
    say(
        c,
        &format!(
            "baked {name}: {} triangles, {} directions × {}² tiles, {:.1} MiB, {:.1} s",
            field.triangle_count(),
            field.parameters().directions,
            field.parameters().tiles,
            field.len_bytes() as f64 / (1u64 << 20) as f64,
            start.elapsed().as_secs_f64()
        ),
    );
    Ok((path, field))
}

/// Runs everything and returns the markdown report.
pub fn run(c: &DynamicConfig) -> Result<String> {
    let mut md = String::new();
    writeln!(md, "# Dynamic scenes: instances, updates and the paper's delete and reinsert\n")?;
    writeln!(
        md,
        "Written by `{}` on {} threads (release build); every time is the median of {} runs after a warm-up run. \
         What each part measures: `crates/vlf-bench/src/dynamic/mod.rs`.\n",
        c.command,
        rayon::current_num_threads(),
        c.repeats
    )?;
    instances(c, &mut md)?;
    edits(c, &mut md)?;
    Ok(md)
}

/// Parts 1 and 2.
fn instances(c: &DynamicConfig, md: &mut String) -> Result<()> {
    let tris = generate::random_cube(c.mesh_triangles, generate::DEFAULT_TRIANGLE_SIZE, 7);
    let (path, field) = bake(c, &BakeScene::from_triangles("mesh", &tris)?, "instanced.vlf", (0, 0))?;
    let field = Arc::new(field);
    let mut rng = Rng::new(11);
    let spread = 2.0 * (c.instances as f64).cbrt();
    let transforms: Vec<Affine> = (0..c.instances).map(|_| random_transform(&mut rng, spread)).collect();
    let mut scene = Scene::new();
    let id = scene.add_field(EditedField::new(field.clone()));
    let start = Instant::now();
    for t in &transforms {
        scene.add_instance(id, *t, u32::MAX)?;
    }
    scene.rebuild();
    let build = start.elapsed().as_secs_f64();
    let (lo, hi) = scene.bounds();
    let center: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt() / 2.0;
    let primary = Camera::outside(center, radius, 1.0).primary_rays(c.resolution, c.resolution);
    let random = incoherent(lo, hi, c.incoherent, 5);

    writeln!(md, "## 1. {} instances of a {}-triangle field\n", c.instances, field.triangle_count())?;
    writeln!(
        md,
        "One field baked once ({}, {} directions × {}² tiles, {:.1} MiB), placed {} times under random rotations, \
         per-axis scales of 0.5 to 1.5 (a quarter of the axes mirrored) and translations in a cube of side {:.0}: \
         {:.1} M triangles in the world. Primary rays: a {}² outside view framing the instances. Incoherent rays: {} \
         with origins uniform in the instances' box and uniform directions.\n",
        path.file_name().and_then(|s| s.to_str()).unwrap_or(""),
        field.parameters().directions,
        field.parameters().tiles,
        field.len_bytes() as f64 / (1u64 << 20) as f64,
        c.instances,
        2.0 * spread,
        c.instances as f64 * field.triangle_count() as f64 / 1e6,
        c.resolution,
        c.incoherent
    )?;
    writeln!(
        md,
        "| contestant | top-level build | primary closest | primary any | incoherent closest | incoherent any |"
    )?;
    writeln!(md, "| --- | ---: | ---: | ---: | ---: | ---: |")?;
    let trace = |rays: &[Ray], any: bool, s: &Scene| {
        timed(c.repeats, || {
            let n: usize = if any {
                rays.par_iter().with_min_len(256).filter(|r| s.any_hit(r, u32::MAX)).count()
            } else {
                rays.par_iter().with_min_len(256).filter(|r| s.closest_hit(r, u32::MAX).is_some()).count()
            };
            std::hint::black_box(n);
        })
    };
    let ours = [
        trace(&primary, false, &scene),
        trace(&primary, true, &scene),
        trace(&random, false, &scene),
        trace(&random, true, &scene),
    ];
    writeln!(
        md,
        "| VLF instances | {:.2} ms | {:.2} Mrays/s | {:.2} Mrays/s | {:.2} Mrays/s | {:.2} Mrays/s |",
        build * 1e3,
        mrays(primary.len(), ours[0]),
        mrays(primary.len(), ours[1]),
        mrays(random.len(), ours[2]),
        mrays(random.len(), ours[3])
    )?;
    say(c, "instances: VLF traced");
    #[cfg(feature = "embree")]
    let mut embree_scene = {
        // The field's triangles in its own (baked) coordinates, which the transforms map to the world.
        let field_tris: Vec<[[f32; 3]; 3]> = (0..field.triangle_count())
            .map(|i| field.triangle(i).expect("in range").map(|v| v.map(|x| x as f32)))
            .collect();
        let mut e = embree::EmbreeInstances::new(&field_tris, c.instances)?;
        for (i, t) in transforms.iter().enumerate() {
            e.set(i as u32, t.rows());
        }
        let start = Instant::now();
        e.commit()?;
        let build = start.elapsed().as_secs_f64();
        let et = |rays: &[Ray], any: bool| {
            timed(c.repeats, || {
                let n: usize = if any {
                    rays.par_iter().with_min_len(256).filter(|r| e.any_hit(r)).count()
                } else {
                    rays.par_iter().with_min_len(256).filter(|r| e.closest_hit(r).is_some()).count()
                };
                std::hint::black_box(n);
            })
        };
        let theirs = [et(&primary, false), et(&primary, true), et(&random, false), et(&random, true)];
        writeln!(
            md,
            "| Embree 3 two-level | {:.2} ms | {:.2} Mrays/s | {:.2} Mrays/s | {:.2} Mrays/s | {:.2} Mrays/s |",
            build * 1e3,
            mrays(primary.len(), theirs[0]),
            mrays(primary.len(), theirs[1]),
            mrays(random.len(), theirs[2]),
            mrays(random.len(), theirs[3])
        )?;
        let (agree, total) = agreement(&scene, &e, &random);
        writeln!(
            md,
            "\nThe two agree (both miss, or hit within a relative 10⁻⁴ in t) on {agree} of {total} incoherent rays; \
             the rest graze an edge, where Embree's f32 transforms and the field's f64 ones round differently.\n"
        )?;
        say(c, "instances: Embree traced");
        e
    };
    #[cfg(not(feature = "embree"))]
    writeln!(md, "\n(Built without the `embree` feature: no Embree row.)\n")?;
    writeln!(
        md,
        "Top-level build: for the field's scene, adding the instances one by one and building its hierarchy (`Scene::rebuild`); for Embree, the first `rtcCommitScene` of the top scene over instances already set (the mesh's BVH was built before, once, as the field was baked once).\n"
    )?;

    // Part 2: updates.
    writeln!(md, "## 2. Moving {} of the {} instances every frame\n", c.updates, c.instances)?;
    writeln!(
        md,
        "Each of {} frames gives {} instances (chosen at random) new random transforms; the time is per frame, \
         everything the structure needs before the next query included. The field's scene refits the top-level \
         hierarchy along each moved instance's path and rebuilds it only when its boxes' area has doubled; \
         Embree rebuilds its top level (`rtcCommitScene`, dynamic scene, low build quality).\n",
        c.frames, c.updates
    )?;
    writeln!(md, "| contestant | update per frame (median) | slowest frame | incoherent closest after the frames |")?;
    writeln!(md, "| --- | ---: | ---: | ---: |")?;
    let mut rng = Rng::new(17);
    let plan: Vec<Vec<(u32, Affine)>> = (0..c.frames)
        .map(|_| {
            (0..c.updates)
                .map(|_| ((rng.next_u64() % c.instances as u64) as u32, random_transform(&mut rng, spread)))
                .collect()
        })
        .collect();
    let rebuilds = scene.rebuilds();
    let mut per: Vec<f64> = plan
        .iter()
        .map(|frame| {
            let start = Instant::now();
            for &(i, t) in frame {
                scene.set_transform(i, t).expect("a live instance");
            }
            start.elapsed().as_secs_f64()
        })
        .collect();
    let worst = per.iter().copied().fold(0.0, f64::max);
    let after = trace(&random, false, &scene);
    writeln!(
        md,
        "| VLF instances | {:.1} µs | {:.1} µs | {:.2} Mrays/s ({} rebuilds in {} frames) |",
        median(&mut per) * 1e6,
        worst * 1e6,
        mrays(random.len(), after),
        scene.rebuilds() - rebuilds,
        c.frames
    )?;
    #[cfg(feature = "embree")]
    {
        let e = &mut embree_scene;
        let mut per: Vec<f64> = plan
            .iter()
            .map(|frame| {
                let start = Instant::now();
                for (i, t) in frame {
                    e.set(*i, t.rows());
                }
                e.commit().expect("commit");
                start.elapsed().as_secs_f64()
            })
            .collect();
        let worst = per.iter().copied().fold(0.0, f64::max);
        let e = &*e;
        let after = timed(c.repeats, || {
            std::hint::black_box(random.par_iter().with_min_len(256).filter(|r| e.closest_hit(r).is_some()).count());
        });
        writeln!(
            md,
            "| Embree 3 top-level rebuild | {:.1} µs | {:.1} µs | {:.2} Mrays/s |",
            median(&mut per) * 1e6,
            worst * 1e6,
            mrays(random.len(), after)
        )?;
    }
    writeln!(md)?;
    drop(scene);
    drop(field);
    std::fs::remove_file(&path)?;
    Ok(())
}

/// How many of `rays` both answer alike (both miss, or both hit with t within a relative 1e-4).
#[cfg(feature = "embree")]
fn agreement(scene: &Scene, e: &embree::EmbreeInstances, rays: &[Ray]) -> (usize, usize) {
    let agree = rays
        .par_iter()
        .filter(|r| match (scene.closest_hit(r, u32::MAX), e.closest_hit(r)) {
            (None, None) => true,
            (Some(a), Some((t, _, _))) => (a.hit.t - t).abs() <= 1e-4 * a.hit.t.abs().max(1.0),
            _ => false,
        })
        .count();
    (agree, rays.len())
}

/// Part 3.
fn edits(c: &DynamicConfig, md: &mut String) -> Result<()> {
    // The big field: the objects as named sources, the rest as another.
    let mut b = SceneBuilder::new();
    let input = b.begin_input("edits", [0; 32]);
    let mut objects = Vec::new();
    let mut used = 0usize;
    for (k, &n) in c.objects.iter().enumerate() {
        let name = format!("object-{n}");
        let source = b.add_source(input, SourceDesc::program(&name));
        let tris: Vec<[[f64; 3]; 3]> = generate::random_cube(n, generate::DEFAULT_TRIANGLE_SIZE, 100 + k as u64)
            .iter()
            .map(|t| t.map(|v| v.map(f64::from)))
            .collect();
        for (i, t) in tris.iter().enumerate() {
            b.push_triangle(source, i as u64, *t)?;
        }
        used += n;
        objects.push((name, tris));
    }
    let rest = b.add_source(input, SourceDesc::program("rest"));
    for (i, t) in generate::random_cube(c.big_triangles.saturating_sub(used), generate::DEFAULT_TRIANGLE_SIZE, 99)
        .iter()
        .enumerate()
    {
        b.push_triangle(rest, i as u64, t.map(|v| v.map(f64::from)))?;
    }
    let big = b.finish()?;
    let (path, field) = bake(c, &big, "edited.vlf", c.big_params)?;
    let field = Arc::new(field);
    let (center, radius) = field.bounding_sphere();
    let lo = center.map(|x| x - 0.6 * radius);
    let hi = center.map(|x| x + 0.6 * radius);
    let rays = incoherent(lo, hi, c.incoherent, 23);
    let query = |f: &EditedField| {
        let o = f.field().origin();
        let local: Vec<Ray> =
            rays.iter().map(|r| Ray { org: std::array::from_fn(|k| (r.org[k] as f64 - o[k]) as f32), ..*r }).collect();
        mrays(
            rays.len(),
            timed(c.repeats, || {
                std::hint::black_box(
                    local.par_iter().with_min_len(256).filter(|r| f.closest_hit_local(r, &mut ()).is_some()).count(),
                );
            }),
        )
    };

    writeln!(md, "## 3. The paper's delete and reinsert in a {}-triangle field\n", field.triangle_count())?;
    writeln!(
        md,
        "One field of {} random triangles ({} directions × {}² tiles, {:.1} MiB) holding objects of {} triangles \
         as named sources. A move is the paper's: remove the object (by name the first time: its mapped ids are \
         marked; then by the ids it was inserted with: the overlay's tiles are rasterised again without them), turn it \
         by 10° about the field's centre (scaled by 0.98 so it stays in the bounding sphere), insert it (rasterised \
         into all {} directions with the bake's kernel). Closest-hit speed: {} incoherent rays inside the field.\n",
        field.triangle_count(),
        field.parameters().directions,
        field.parameters().tiles,
        field.len_bytes() as f64 / (1u64 << 20) as f64,
        c.objects.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" and "),
        field.parameters().directions,
        rays.len()
    )?;
    let base = query(&EditedField::new(field.clone()));
    writeln!(md, "Unedited: **{base:.2} Mrays/s**.\n")?;
    writeln!(
        md,
        "| object | first move (from the mapped field) | later moves (median) | closest hit after 1 move | after {} moves |",
        c.moves
    )?;
    writeln!(md, "| ---: | ---: | ---: | ---: | ---: |")?;
    for (name, tris) in &objects {
        let mut f = EditedField::new(field.clone());
        let mut angle = 0.0;
        let turn = |angle: f64| {
            let r = Affine::rotation_about([0.3, 1.0, 0.2], angle.to_radians(), center).expect("a rotation");
            let s = Affine::from_3x4(std::array::from_fn(|i| {
                let mut row = [0.0; 4];
                row[i] = 0.98;
                row[3] = 0.02 * center[i];
                row
            }))
            .expect("a scale");
            r.then_after(&s).expect("usable")
        };
        let start = Instant::now();
        f.remove_object(Object::Name(name))?;
        angle += 10.0;
        let mut ids = f.insert(tris, &turn(angle))?;
        let first = start.elapsed().as_secs_f64();
        let after_one = query(&f);
        let mut later = Vec::new();
        for _ in 1..c.moves.max(2) {
            let start = Instant::now();
            let old: Vec<u32> = ids.clone().collect();
            f.remove(&old)?;
            angle += 10.0;
            ids = f.insert(tris, &turn(angle))?;
            later.push(start.elapsed().as_secs_f64());
        }
        let after_many = query(&f);
        writeln!(
            md,
            "| {} triangles | {:.1} ms | {:.1} ms | {:.2} Mrays/s ({:+.0}%) | {:.2} Mrays/s ({:+.0}%) |",
            tris.len(),
            first * 1e3,
            median(&mut later) * 1e3,
            after_one,
            100.0 * (after_one / base - 1.0),
            after_many,
            100.0 * (after_many / base - 1.0)
        )?;
        say(c, &format!("edits: {name} moved {} times", c.moves.max(2)));
    }
    #[cfg(feature = "embree")]
    {
        let world: Vec<[[f32; 3]; 3]> = big.world_vertices().iter().map(|t| t.map(|v| v.map(|x| x as f32))).collect();
        let e = crate::peers::embree::EmbreeContestant::build(&world)?;
        use crate::peers::contestant::Contestant;
        writeln!(
            md,
            "\nFor scale: Embree 3 builds its BVH over the whole {}-triangle mesh (what a structure without edits \
             does after any change) in {:.1} ms here.",
            world.len(),
            e.build_seconds() * 1e3
        )?;
    }
    writeln!(
        md,
        "\nRemoved mapped triangles stay in the mapped leaves (the file is never written), so rays there still test \
         their boxes; inserted triangles live in an overlay with tiles of its own, walked after the mapped field's."
    )?;
    writeln!(
        md,
        "\n## Notes\n\n- The machine's cores are shared with other work: the same run repeated gives speeds that differ by up to about 40% from run to run. The contestants of one table ran seconds apart in the same process, on the same rays; compare within a table.\n- A moved instance whose new box leaves its parent's is taken out of the hierarchy and inserted again where its box grows the tree least; one that stays inside is refitted in place. The hierarchy is rebuilt when the inner boxes' area has doubled since the last build. Queries after many moves are therefore somewhat slower than after a build (compare the incoherent column of part 2 with part 1); `Scene::rebuild` restores them.\n- The first move of an object removes mapped triangles (a bitset) and inserts into a new overlay, whose tiles it allocates; later moves also rasterise the previous copy again to take its ids out of the overlay's tiles, the paper's delete."
    )?;
    drop(field);
    std::fs::remove_file(&path)?;
    Ok(())
}
