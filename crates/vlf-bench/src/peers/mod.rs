//! `vlf-bench peers`: the visibility field against Embree 3 (`embree` feature), obvhs's CWBVH
//! (`obvhs` feature) and the paper's kd-tree, on the same scenes and the same rays, in one
//! process; every contestant's hits checked against the brute force; Mrays/s at each thread
//! count, build times and sizes, written as `peers.md`, `peers.json` and SVG plots.
//!
//! The flow per scene: load the triangles ([`scenes`]); bake the field at its default automatic
//! parameters and open it; make the ray sets ([`rays`]; the shadow rays start from the field's
//! primary hits); build the other contestants; check a sample of every set against the brute
//! force ([`check`]); time every contestant on every set at each thread count, the contestants
//! taking turns run by run ([`time_round_robin`]);
//! with `--sweep`, bake the field again at explicit parameters and time it. The report
//! ([`report`]) is rewritten after every scene, so a long run leaves its finished scenes behind.

pub mod check;
pub mod contestant;
#[cfg(feature = "embree")]
#[allow(unsafe_code)] // The FFI to Embree's C shim: every unsafe block says why it is sound.
pub mod embree;
pub mod model;
#[cfg(feature = "obvhs")]
pub mod obvhs;
pub mod rays;
pub mod report;
pub mod rounds;
pub mod scenes;

use crate::latency;
use crate::median;
use anyhow::Context as _;
use contestant::{Contestant, FieldBatch, FieldContestant, KdContestant, PeerHit};
pub use model::*;
use rayon::prelude::*;
use rays::RaySet;
use scenes::{LoadedScene, SceneSpec};
use std::hint::black_box;
use std::time::Instant;
use vlf_bake::BakeConfig;
use vlf_geom::{Camera, Ray};

/// Rays per parallel work item.
const CHUNK: usize = 1024;
/// The seed of the incoherent rays and of the checked samples.
const SEED: u64 = 12;

fn note(verbose: bool, msg: impl std::fmt::Display) {
    if verbose {
        eprintln!("peers: {msg}");
    }
}

fn field_info(f: &FieldContestant, triangles: usize) -> FieldInfo {
    FieldInfo {
        directions: f.directions,
        tiles: f.tiles,
        bake_s: f.bake_seconds,
        open_ms: f.open_seconds * 1e3,
        bytes: f.file_bytes,
        bytes_per_triangle: f.file_bytes as f64 / triangles.max(1) as f64,
        choice: f.choice.clone(),
    }
}

/// One timed run of `c` over `set` in `pool`: rays in chunks of `CHUNK` (1,024) that the pool's
/// threads take in turn, one query per ray; the answers go to `closest` or `any`. Seconds.
fn run_once(
    c: &dyn Contestant,
    set: &RaySet,
    pool: &rayon::ThreadPool,
    closest: &mut [Option<PeerHit>],
    any: &mut [bool],
) -> f64 {
    let start = Instant::now();
    pool.install(|| match set.query {
        Query::Closest => set
            .rays
            .par_chunks(CHUNK)
            .zip(closest.par_chunks_mut(CHUNK))
            .for_each(|(r, o)| c.closest_hits(black_box(r), o)),
        Query::Any => {
            set.rays.par_chunks(CHUNK).zip(any.par_chunks_mut(CHUNK)).for_each(|(r, o)| c.any_hits(black_box(r), o))
        }
    });
    let s = start.elapsed().as_secs_f64();
    black_box((&closest, &any));
    s
}

/// Times `c` on `set` in `pool`: one warm-up run, then `repeats` timed runs back to back.
/// Returns the median and the runs, in seconds.
pub fn time_set(c: &dyn Contestant, set: &RaySet, pool: &rayon::ThreadPool, repeats: usize) -> (f64, Vec<f64>) {
    let mut closest: Vec<Option<PeerHit>> = vec![None; set.rays.len()];
    let mut any = vec![false; set.rays.len()];
    run_once(c, set, pool, &mut closest, &mut any);
    let runs: Vec<f64> = (0..repeats.max(1)).map(|_| run_once(c, set, pool, &mut closest, &mut any)).collect();
    let mut sorted = runs.clone();
    (median(&mut sorted), runs)
}

/// Times every contestant of `all` on `set` in `pool`, in rounds: a warm-up run of each, then
/// `repeats` rounds in which each contestant runs once, in turn. A slow spell of the machine (a
/// neighbour on the host, a frequency change) then falls on every contestant alike instead of on
/// whichever was running, and run `k` of one contestant can be paired with run `k` of another
/// ([`rounds::ratio`] takes the median of those paired ratios). Before each round every thread of
/// the pool times [`latency::core_probe_ns`], and the round keeps the slowest: how fast the cores
/// computed then, which tells the rounds that fell in one of the host's slow spells (a pair of
/// runs in one cancels the spell only partly: the field loses more speed in it than Embree).
/// Returns each contestant's median and runs, in seconds, in `all`'s order, and the rounds' probes.
pub fn time_round_robin(
    all: &[&dyn Contestant],
    set: &RaySet,
    pool: &rayon::ThreadPool,
    repeats: usize,
) -> (Vec<(f64, Vec<f64>)>, Vec<f64>) {
    let mut closest: Vec<Option<PeerHit>> = vec![None; set.rays.len()];
    let mut any = vec![false; set.rays.len()];
    for c in all {
        run_once(*c, set, pool, &mut closest, &mut any);
    }
    let mut runs = vec![Vec::with_capacity(repeats.max(1)); all.len()];
    let mut probes = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
        probes.push(pool.broadcast(|_| latency::core_probe_ns()).into_iter().fold(0.0, f64::max));
        for (c, r) in all.iter().zip(&mut runs) {
            r.push(run_once(*c, set, pool, &mut closest, &mut any));
        }
    }
    let timed = runs
        .into_iter()
        .map(|r| {
            let mut sorted = r.clone();
            (median(&mut sorted), r)
        })
        .collect();
    (timed, probes)
}

fn pools(threads: &[usize]) -> anyhow::Result<Vec<(usize, rayon::ThreadPool)>> {
    threads.iter().map(|&n| Ok((n, rayon::ThreadPoolBuilder::new().num_threads(n).build()?))).collect()
}

/// The contestants other than the field, in table order.
fn build_peers(
    tris: &[Tri],
    cfg: &PeersConfig,
    center: [f64; 3],
    radius: f64,
) -> anyhow::Result<Vec<Box<dyn Contestant>>> {
    let mut v: Vec<Box<dyn Contestant>> = Vec::new();
    #[cfg(feature = "embree")]
    {
        note(cfg.verbose, "building Embree");
        v.push(Box::new(embree::EmbreeContestant::build(tris)?));
    }
    #[cfg(feature = "obvhs")]
    {
        note(cfg.verbose, "building obvhs");
        v.push(Box::new(obvhs::ObvhsContestant::build(tris)));
    }
    note(cfg.verbose, format!("building the kd-tree ({:?})", cfg.kd));
    let probe: Vec<Ray> = [Camera::outside(center, radius, 1.0), Camera::inside(center, radius, 1.0)]
        .iter()
        .flat_map(|c| c.primary_rays(128, 128))
        .collect();
    v.push(Box::new(KdContestant::build(tris, cfg.kd, &probe)));
    Ok(v)
}

/// The ray sets of a scene; the shadow sets start from `field`'s primary hits.
fn ray_sets(scene: &LoadedScene, field: &FieldContestant, cfg: &PeersConfig) -> (Vec<RaySet>, [f64; 3]) {
    let (center, radius) = field.field.bounding_sphere();
    let light = rays::light(center, radius);
    let [outside, inside] = rays::primary(center, radius, cfg.resolution);
    let incoherent = rays::incoherent(&scene.triangles, cfg.incoherent, SEED);
    let hits = |set: &RaySet| -> Vec<Option<f32>> {
        set.rays.par_iter().with_min_len(256).map(|r| field.closest_hit(r).map(|h| h.t)).collect()
    };
    let shadow_outside = rays::shadow("shadow-outside", &outside.rays, &hits(&outside), light);
    let shadow_inside = rays::shadow("shadow-inside", &inside.rays, &hits(&inside), light);
    (vec![outside, inside, incoherent, shadow_outside, shadow_inside], light)
}

/// Runs one scene.
pub fn run_scene(spec: &SceneSpec, cfg: &PeersConfig) -> anyhow::Result<SceneResult> {
    let start = Instant::now();
    let mut scene = spec.load()?;
    // The scene as the field stores it (degenerate triangles dropped, duplicates merged, relative
    // to its centre): every contestant gets its triangles, in world coordinates, so that triangle
    // ids agree; the brute force checks on the stored ones, with the field's own arithmetic.
    let baked = vlf_bake::Scene::from_triangles(&scene.name, &scene.triangles).context("scene")?;
    scene.triangles = baked.world_vertices().iter().map(|t| t.map(|v| v.map(|c| c as f32))).collect();
    let stored = baked.vertices();
    let n = scene.triangles.len();
    note(cfg.verbose, format!("{}: {}", scene.name, scene.description));
    note(cfg.verbose, format!("{}: baking the field (default parameters)", scene.name));
    let mut field = FieldContestant::bake(&baked, &BakeConfig::default(), &cfg.work, &scene.name)?;
    field.keep = cfg.keep_fields;
    let info = field_info(&field, n);
    note(
        cfg.verbose,
        format!(
            "{}: {} in {:.1} s, {:.0} B/triangle",
            scene.name,
            field.describe(),
            info.bake_s,
            info.bytes_per_triangle
        ),
    );
    let (center, radius) = field.field.bounding_sphere();
    let (sets, light) = ray_sets(&scene, &field, cfg);
    let peers = build_peers(&scene.triangles, cfg, center, radius)?;
    let batch = FieldBatch(&field);
    let mut all: Vec<&dyn Contestant> = vec![&field, &batch];
    all.extend(peers.iter().map(|b| b.as_ref()));
    let built = all
        .iter()
        .map(|c| Built {
            contestant: c.name().into(),
            params: c.describe(),
            build_s: c.build_seconds(),
            bytes: c.bytes(),
            bytes_per_triangle: c.bytes() as f64 / n.max(1) as f64,
        })
        .collect();

    let pools = pools(&cfg.threads)?;
    let mut results = Vec::new();
    for (k, set) in sets.iter().enumerate() {
        let sample = if n < cfg.check_all_below { set.rays.len() } else { cfg.check_rays };
        note(
            cfg.verbose,
            format!(
                "{} / {}: brute force on {} of {} rays",
                scene.name,
                set.name,
                sample.min(set.rays.len()),
                set.rays.len()
            ),
        );
        let checked =
            check::Checked::new(&stored, baked.center, set, &rays::sample(set.rays.len(), sample, SEED + k as u64));
        let checks: Vec<Counts> = all.iter().map(|c| checked.compare(*c, cfg.t_tolerance)).collect();
        let memory_latency_ns = latency::chase(latency::PEERS_WORKING_SET_MIB << 20)?;
        note(cfg.verbose, format!("{} / {}: a miss to memory costs {memory_latency_ns:.1} ns", scene.name, set.name));
        let mut speeds = Vec::new();
        for (threads, pool) in &pools {
            let load = load_average();
            let (timed, core_probe_ns) = time_round_robin(&all, set, pool, cfg.repeats);
            for (c, (median_s, runs_s)) in all.iter().zip(timed) {
                let mrays_per_s = set.rays.len() as f64 / median_s / 1e6;
                note(
                    cfg.verbose,
                    format!("{} / {} / {} / {threads}T: {mrays_per_s:.3} Mrays/s", scene.name, set.name, c.name()),
                );
                speeds.push(Speed {
                    contestant: c.name().into(),
                    threads: *threads,
                    median_s,
                    runs_s,
                    mrays_per_s,
                    load,
                    core_probe_ns: core_probe_ns.clone(),
                });
            }
        }
        let hits = match set.query {
            Query::Closest => set.rays.par_iter().filter(|r| field.closest_hit(r).is_some()).count(),
            Query::Any => set.rays.par_iter().filter(|r| field.any_hit(r)).count(),
        };
        results.push(SetResult {
            name: set.name.into(),
            query: set.query,
            rays: set.rays.len(),
            hits,
            memory_latency_ns: Some(memory_latency_ns),
            speeds,
            checks,
        });
    }
    drop(peers);
    drop(field);

    let mut sweep = Vec::new();
    let mut sweep_skipped = Vec::new();
    for &(directions, tiles) in &cfg.sweep {
        let config = BakeConfig { directions: Some(directions), tiles: Some(tiles), ..BakeConfig::default() };
        note(cfg.verbose, format!("{}: sweep: baking {directions} directions × {tiles}²", scene.name));
        let name = format!("{}-sweep-{directions}x{tiles}", scene.name);
        let f = match FieldContestant::bake(&baked, &config, &cfg.work, &name) {
            Ok(f) => f,
            Err(e) => {
                sweep_skipped.push(format!("{directions} directions × {tiles}²: {e:#}"));
                continue;
            }
        };
        let mut speeds = Vec::new();
        for set in &sets {
            for (threads, pool) in &pools {
                let (median_s, _) = time_set(&f, set, pool, cfg.repeats);
                speeds.push((set.name.to_string(), *threads, set.rays.len() as f64 / median_s / 1e6));
            }
        }
        sweep.push(SweepPoint { field: field_info(&f, n), speeds });
    }
    Ok(SceneResult {
        name: scene.name,
        description: scene.description,
        triangles: n,
        field: info,
        built,
        sets: results,
        sweep,
        sweep_skipped,
        light,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Runs every scene, rewriting the report after each; fails if the field disagreed with the
/// brute force anywhere (after writing the report that shows where).
pub fn run(cfg: &PeersConfig) -> anyhow::Result<report::Report> {
    let mut report = report::Report::new(cfg);
    let start = Instant::now();
    for spec in &cfg.scenes {
        let scene = run_scene(spec, cfg)?;
        report.scenes.push(scene);
        report.total_seconds = start.elapsed().as_secs_f64();
        report.load_after = load_average();
        report.write(&cfg.out)?;
    }
    let bad: Vec<String> = report
        .scenes
        .iter()
        .flat_map(|s| {
            s.sets.iter().flat_map(move |set| {
                set.checks.iter().filter(|c| c.contestant.starts_with("field") && c.inexact() > 0).map(move |c| {
                    format!(
                        "{} / {} / {}: {} of {} rays differ from the brute force",
                        s.name,
                        set.name,
                        c.contestant,
                        c.inexact(),
                        c.rays
                    )
                })
            })
        })
        .collect();
    anyhow::ensure!(bad.is_empty(), "the field disagrees with the brute force:\n{}", bad.join("\n"));
    Ok(report)
}
