//! `trace --scene` and `render --scene`: the same commands over a scene file of instances
//! (`formats/scene.md`, `vlf_scene`) instead of one field.

use super::picture::{setup, summarise};
use crate::args::{RenderArgs, TraceArgs};
use crate::progress::Bar;
use anyhow::{Context, Result, anyhow, bail};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;
use std::time::Instant;
use vlf_bake::Progress;
use vlf_bake::atomic::write_atomically;
use vlf_render::{SceneBounds, SceneOptions};
use vlf_runtime::{Hit, OpenOptions, Ray};
use vlf_scene::{Affine, Scene, SceneFile};

/// Reads, checks and loads a scene file: fields opened once each, meshes to insert read with the
/// bake's importer. The scene file must be a regular file (a device would be read without end, a
/// pipe waited on); so must the fields (`Field::open`) and meshes (the importer) it names: each
/// reader refuses anything else (`vlf_runtime::regular`). Packed fields are held to the memory
/// budget all together, as `super::open_field` holds one given alone.
pub fn load(path: &Path) -> Result<Scene> {
    let meshes = |p: &Path| vlf_bake::import::import_paths(&[p]).map(|s| s.world_vertices()).map_err(|e| e.to_string());
    let mut options = OpenOptions::new();
    options.max_unpacked_bytes(vlf_bake::memory::budget().0);
    Ok(SceneFile::read(path)?.load_with(&meshes, &options)?)
}

/// `trace --scene`: one hit per ray (`prim` the triangle in the hit instance's field) and, with
/// `--instance-ids`, the instance per ray. Returns the hits and the seconds spent tracing.
pub fn trace(a: &TraceArgs, scene_path: &Path, rays: &[Ray]) -> Result<(Vec<Hit>, f64)> {
    let scene = load(scene_path)?;
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut ids = vec![u32::MAX; rays.len()];
    let start = Instant::now();
    rays.par_iter().zip(hits.par_iter_mut().zip(ids.par_iter_mut())).with_min_len(256).for_each(|(r, (h, id))| {
        let found =
            if a.any_hit { scene.any_hit_counted(r, u32::MAX, &mut ()) } else { scene.closest_hit(r, u32::MAX) };
        if let Some(f) = found {
            (*h, *id) = (f.hit, f.instance);
        }
    });
    let seconds = start.elapsed().as_secs_f64();
    if let Some(path) = &a.instance_ids {
        write_atomically(path, |w| w.write_all(bytemuck::cast_slice(&ids)))
            .with_context(|| format!("cannot write instance ids file {}", path.display()))?;
    }
    Ok((hits, seconds))
}

/// Bytes the renderer holds per triangle of the flattened scene (`vlf_render::Scene::
/// from_instances`): its world-space vertices (36) and surface (4); with smoothing, its corner
/// normals (36) and, while they are computed, its face normals (48) and its corners' sort keys (60).
const FLAT_BYTES_PER_TRIANGLE: (u64, u64) = (36 + 4, 36 + 4 + 36 + 48 + 60);

/// Refuses a scene whose flattening for the renderer (every instance's triangles copied to world
/// space, numbered as [`Scene::flat`] numbers them) passes the 2³² − 1 triangle ids or needs more
/// memory than this process can still allocate: checked before any of it is made, since a few
/// megabytes of scene file can instance one field hundreds of thousands of times.
fn check_flattened(scene: &Scene, path: &Path, smooth: bool) -> Result<()> {
    let fields = scene.fields();
    let triangles: u64 = scene
        .instance_ids()
        .filter_map(|id| scene.instance(id))
        .filter_map(|info| fields.get(info.field.0 as usize))
        .map(|f| f.id_count() as u64)
        .sum();
    let instances = scene.instance_count();
    let what = format!("scene file {}: its {instances} instances hold {triangles} triangles", path.display());
    if triangles > u32::MAX as u64 {
        bail!("{what}, more than the {} a picture can number (u32 triangle ids)", u32::MAX);
    }
    let per = if smooth { FLAT_BYTES_PER_TRIANGLE.1 } else { FLAT_BYTES_PER_TRIANGLE.0 };
    crate::limits::check_memory(
        triangles.saturating_mul(per),
        &format!("{what}; copying them to world space for the renderer"),
    )
}

/// The transform of a moved instance at animation time `s` (0 at the first frame, 1 at the
/// last): turned by `s · spin` degrees about `up` through `centre`, then moved by `s · path`.
fn moved(start: &Affine, s: f64, path: [f64; 3], spin: f64, up: [f64; 3], centre: [f64; 3]) -> Result<Affine> {
    let turn = Affine::rotation_about(up, (s * spin).to_radians(), centre)
        .ok_or_else(|| anyhow!("--up {up:?} cannot be turned about"))?;
    let shift = Affine::translation(path.map(|p| s * p));
    shift
        .then_after(&turn)
        .and_then(|m| m.then_after(start))
        .ok_or_else(|| anyhow!("the moved transform at time {s} is not usable (it over- or underflows)"))
}

/// `render --scene`: one picture, or with `--frames N` an animated PNG of the `--move` instances
/// travelling along `--path` and turning by `--spin`. The camera frames every frame's scene.
pub fn render(a: &RenderArgs) -> Result<()> {
    let path = a.scene.as_deref().expect("clap requires a field or --scene");
    let mut scene = load(path)?;
    let frames = a.frames.unwrap_or(1);
    let last = scene.instance_ids().last().ok_or_else(|| anyhow!("scene file {} has no instances", path.display()))?;
    let moves = if a.moves.is_empty() { vec![last] } else { a.moves.clone() };
    let mut starts = Vec::with_capacity(moves.len());
    for &id in &moves {
        let info = scene
            .instance(id)
            .ok_or_else(|| anyhow!("--move {id}: scene file {} has instances 0 to {last}", path.display()))?;
        let (lo, hi) = scene.instance_bounds(id).unwrap_or(([0.0; 3], [0.0; 3]));
        starts.push((id, info.transform, std::array::from_fn::<f64, 3, _>(|k| 0.5 * (lo[k] + hi[k]))));
    }
    let (lo, hi) = scene.content_bounds();
    if !(0..3).all(|k| lo[k] <= hi[k]) {
        bail!("scene file {} has no triangles to render", path.display());
    }
    let travel = a.path.unwrap_or([0.5 * (hi[0] - lo[0]), 0.0, 0.0]);
    let time = |k: u32| if frames > 1 { k as f64 / (frames - 1) as f64 } else { 0.0 };
    let place = |scene: &mut Scene, k: u32| -> Result<()> {
        if frames > 1 {
            for &(id, start, centre) in &starts {
                scene.set_transform(id, moved(&start, time(k), travel, a.spin, a.up, centre)?)?;
            }
        }
        Ok(())
    };
    // The box of every frame, so that the camera sees the whole animation.
    let (mut min, mut max) = (lo, hi);
    for k in 0..frames {
        place(&mut scene, k)?;
        let (l, h) = scene.content_bounds();
        for i in 0..3 {
            (min[i], max[i]) = (min[i].min(l[i]), max[i].max(h[i]));
        }
    }
    // Rays are traced relative to the centre of each frame's scene (`Flat`'s origin), so a small
    // scene far from the world's origin renders as it would at the origin.
    let bounds = SceneBounds::of_box(min, max);
    let s = setup(a, &[], &[], &bounds, &path.display().to_string(), frames)?;
    let options = SceneOptions { smooth: !a.flat, ..SceneOptions::default() };
    check_flattened(&scene, path, options.smooth)?;
    let bar = Bar::new(a.quiet || a.json);
    bar.begin("rendering rows", s.settings.height as u64 * frames as u64);
    let start = Instant::now();
    let mut pictures = Vec::with_capacity(frames as usize);
    let mut total: Option<vlf_render::Frame> = None;
    for k in 0..frames {
        place(&mut scene, k)?;
        let flat = scene.flat()?;
        let shading = vlf_render::Scene::from_instances(&scene, &flat, &options);
        let frame = vlf_render::render(&flat, &shading, &s.view, &s.lights, &s.settings, &|rows| bar.advance(rows));
        pictures.push(vlf_render::to_srgb8(&frame, a.exposure));
        total = Some(match total {
            None => frame,
            Some(mut t) => {
                let (r, f) = (&mut t.rays, &frame.rays);
                (r.primary, r.shadow, r.reflection, r.refraction) = (
                    r.primary + f.primary,
                    r.shadow + f.shadow,
                    r.reflection + f.reflection,
                    r.refraction + f.refraction,
                );
                t.total_work.add(&frame.total_work);
                // The work picture is the last frame's.
                t.work = frame.work;
                t
            }
        });
    }
    let seconds = start.elapsed().as_secs_f64();
    bar.end();
    let frame = total.expect("at least one frame");
    let png = if frames > 1 {
        vlf_render::encode_apng(frame.width, frame.height, &pictures, a.frame_ms)?
    } else {
        vlf_render::encode_png(frame.width, frame.height, &pictures[0])?
    };
    write_atomically(&a.output, |w| w.write_all(&png))
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    summarise(a, &s, &frame, a.frames, seconds)
}
