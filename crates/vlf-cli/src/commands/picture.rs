//! What `render` shares between a field and a scene (`--scene`): the camera, size, lights and
//! settings the flags choose, the memory check, the work picture and the summary. Which camera
//! and lights are used is `vlf_render::setup`'s decision.

use super::stdout_line;
use crate::args::{RenderArgs, View, WorkArg};
use crate::limits::check_memory;
use crate::values::BadUsage;
use anyhow::{Context, Result, anyhow};
use std::io::Write;
use std::path::PathBuf;
use vlf_bake::atomic::write_atomically;
use vlf_bake::params::human_bytes;
use vlf_render::setup::{CameraChoice, CameraError, CameraRequest, Framing, LightChoice, choose_camera, choose_lights};
use vlf_render::{Background, Frame, SceneBounds, Settings, WorkMetric};

/// What `render` prints, and its `--json` keys.
#[derive(serde::Serialize)]
struct RenderSummary {
    output: PathBuf,
    width: u32,
    height: u32,
    /// The frames of an animation (`--scene --frames`); absent for one picture.
    #[serde(skip_serializing_if = "Option::is_none")]
    frames: Option<u32>,
    samples_per_pixel: u32,
    camera: String,
    lights: String,
    light_count: usize,
    seconds: f64,
    rays: RaysSummary,
    mrays_per_s: f64,
    work: WorkSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    work_image: Option<WorkImageSummary>,
    threads: usize,
}

#[derive(serde::Serialize)]
struct RaysSummary {
    primary: u64,
    shadow: u64,
    reflection: u64,
    refraction: u64,
    total: u64,
}

#[derive(serde::Serialize)]
struct WorkSummary {
    rays_reaching_the_scene: u64,
    tiles: u64,
    leaves: u64,
    triangle_tests: u64,
}

#[derive(serde::Serialize)]
struct WorkImageSummary {
    path: PathBuf,
    metric: &'static str,
    scale_max: u64,
    max: u64,
    mean: f64,
}

/// The camera, picture size and lights of a render, as the flags and the scene's own cameras and
/// lights choose them; `source` names the field or scene in messages.
pub(super) struct Setup {
    pub view: vlf_render::View,
    pub camera: String,
    pub lights: Vec<vlf_render::Light>,
    pub lights_name: &'static str,
    pub settings: Settings,
}

pub(super) fn setup(
    a: &RenderArgs,
    cameras: &[vlf_runtime::SceneCamera<'_>],
    field_lights: &[vlf_runtime::SceneLight<'_>],
    bounds: &SceneBounds,
    source: &str,
    frames: u32,
) -> Result<Setup> {
    let request = CameraRequest {
        camera: a.camera,
        framing: a.view.map(|v| match v {
            View::Outside => Framing::Outside,
            View::Inside => Framing::Inside,
        }),
        eye: a.eye,
        target: a.target,
        up: a.up,
        fov_degrees: a.fov,
        width: a.width,
        height: a.height,
    };
    let CameraChoice { view, width, height, description: camera } =
        choose_camera(&request, cameras, bounds).map_err(|e| match e {
            CameraError::NoSuchCamera { index, count } => anyhow!("--camera {index}: {source} has {count} camera(s)"),
            CameraError::Degenerate { index } => {
                anyhow!("camera {index} of {source} cannot be used: its frame is degenerate")
            }
            CameraError::EyeIsTarget => BadUsage("--eye and --target are the same point".into()).into(),
            CameraError::UpAlongSight => BadUsage(format!(
                "--up {} is along the line of sight from --eye to the target, so it gives the picture no up: \
                 give a direction across it",
                a.up.map(|c| c.to_string()).join(",")
            ))
            .into(),
            CameraError::SightOutOfRange { distance } => BadUsage(format!(
                "--eye {} is {} the target for double precision (their distance is {distance:e}): no line of sight \
                 can be aimed; place them between about 1e-150 and 1e150 apart",
                a.eye.map_or_else(String::new, |e| e.map(|c| format!("{c:?}")).join(",")),
                if distance == 0.0 { "too close to" } else { "too far from" }
            ))
            .into(),
        })?;
    // Before anything of the picture's size is allocated.
    let (frame_bytes, picture_bytes) =
        (Frame::bytes(width, height), vlf_render::picture_bytes_at_most(width, height, a.work_image.is_some()));
    let pictures = picture_bytes.saturating_mul(frames as u64);
    let what = if a.work_image.is_some() { "picture and work picture" } else { "picture" };
    let count = if frames == 1 { "a".to_string() } else { format!("{frames}") };
    let noun = if frames == 1 { "picture" } else { "pictures" };
    check_memory(
        frame_bytes.saturating_add(pictures),
        &format!(
            "{count} {width}×{height} {noun} (frame {}, {what} {})",
            human_bytes(frame_bytes),
            human_bytes(pictures)
        ),
    )?;
    let LightChoice { lights, description: lights_name } =
        choose_lights(&a.lights, a.default_lights, field_lights, &view, bounds.center, bounds.radius);
    let settings = Settings {
        width,
        height,
        samples: a.samples,
        max_depth: a.bounces,
        ambient: a.ambient,
        background: a.background.map_or(Background::Sky, Background::Solid),
    };
    Ok(Setup { view, camera, lights, lights_name, settings })
}

/// Writes the work picture of `frame` if asked, then prints the summary: `frame`'s rays and work
/// are the whole render's (summed over frames by the caller); `frames` is `Some` for an animation.
pub(super) fn summarise(a: &RenderArgs, s: &Setup, frame: &Frame, frames: Option<u32>, seconds: f64) -> Result<()> {
    let work_image = match &a.work_image {
        None => None,
        Some(path) => {
            let metric = match a.work {
                WorkArg::Tests => WorkMetric::TriangleTests,
                WorkArg::Tiles => WorkMetric::Cells,
                WorkArg::Leaves => WorkMetric::Leaves,
                WorkArg::Rays => WorkMetric::Rays,
            };
            let image = vlf_render::work_image(frame, metric, a.work_max);
            let png = vlf_render::encode_png(frame.width, frame.height, &image.rgb)?;
            write_atomically(path, |w| w.write_all(&png))
                .with_context(|| format!("cannot write {}", path.display()))?;
            Some(WorkImageSummary {
                path: path.clone(),
                metric: metric.describe(),
                scale_max: image.scale_max,
                max: image.max,
                mean: image.mean,
            })
        }
    };
    let r = frame.rays;
    let summary = RenderSummary {
        output: a.output.clone(),
        width: frame.width,
        height: frame.height,
        frames,
        samples_per_pixel: a.samples * a.samples,
        camera: s.camera.clone(),
        lights: s.lights_name.to_string(),
        light_count: s.lights.len(),
        seconds,
        rays: RaysSummary {
            primary: r.primary,
            shadow: r.shadow,
            reflection: r.reflection,
            refraction: r.refraction,
            total: r.total(),
        },
        mrays_per_s: r.total() as f64 / seconds.max(1e-12) / 1e6,
        work: WorkSummary {
            rays_reaching_the_scene: frame.total_work.rays,
            tiles: frame.total_work.cells,
            leaves: frame.total_work.leaves,
            triangle_tests: frame.total_work.triangle_tests,
        },
        work_image,
        threads: rayon::current_num_threads(),
    };
    if a.json {
        return stdout_line(&serde_json::to_string(&summary)?);
    }
    if a.quiet {
        return Ok(());
    }
    let s = &summary;
    let frames = s.frames.map_or(String::new(), |n| format!(", {n} frames"));
    let mut text = format!(
        "rendered {} ({}×{}{frames}, {} samples per pixel) in {:.2} s: {} rays ({} primary, {} shadow, {} reflected, {} refracted), {:.2} Mrays/s on {} threads\n  camera {}; {} light(s), {}",
        s.output.display(),
        s.width,
        s.height,
        s.samples_per_pixel,
        s.seconds,
        s.rays.total,
        s.rays.primary,
        s.rays.shadow,
        s.rays.reflection,
        s.rays.refraction,
        s.mrays_per_s,
        s.threads,
        s.camera,
        s.light_count,
        s.lights
    );
    if let Some(w) = &s.work_image {
        text.push_str(&format!(
            "\n  work picture {}: {} per pixel, black = 0 to white = {} (largest {}, mean {:.1})",
            w.path.display(),
            w.metric,
            w.scale_max,
            w.max,
            w.mean
        ));
    }
    stdout_line(&text)
}
