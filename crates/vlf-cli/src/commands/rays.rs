//! `vlf-bake rays`: a rays file of primary rays for a camera that frames a field's scene, the
//! camera of `render --view` (`vlf_render::setup`). Streamed to the file row by row, after the
//! file system was checked to have room for all of it.

use super::stdout_line;
use crate::args::{RaysArgs, View};
use crate::distinct::{Writes, check_outputs};
use crate::limits::check_disk;
use anyhow::{Context, Result};
use std::io::Write;
use vlf_bake::atomic::write_atomically;
use vlf_bake::params::human_bytes;
use vlf_render::SceneBounds;
use vlf_render::setup::{CameraRequest, Framing, choose_camera};
use vlf_runtime::Ray;

/// What `rays` prints, and its `--json` keys.
#[derive(serde::Serialize)]
struct RaysSummary<'a> {
    output: &'a std::path::Path,
    rays: u64,
    width: u32,
    height: u32,
    view: &'static str,
    bytes: u64,
}

/// `vlf-bake rays`: writes one primary ray per pixel of the camera framing the field's scene.
pub fn run(a: &RaysArgs) -> Result<()> {
    check_outputs(&[("FIELD", &a.field)], &[("-o/--output", &a.output)], Writes::Through)?;
    let field = super::open_field(&a.field)?;
    let (framing, view_name) = match a.view {
        View::Outside => (Framing::Outside, "outside"),
        View::Inside => (Framing::Inside, "inside"),
    };
    let request = CameraRequest {
        camera: None,
        framing: Some(framing),
        eye: None,
        target: None,
        up: [0.0, 1.0, 0.0],
        fov_degrees: 50.0,
        width: a.width,
        height: a.height,
    };
    let bounds = SceneBounds::of(&field);
    if let Some(warning) = bounds.f32_warning() {
        eprintln!("warning: {}: {warning}", a.field.display());
    }
    let choice = choose_camera(&request, &[], &bounds)?;
    let (width, height) = (choice.width, choice.height);
    let rays = width as u64 * height as u64;
    let bytes = rays * size_of::<Ray>() as u64;
    check_disk(&a.output, bytes, false, &format!("the rays file of {width}×{height} rays"))?;
    write_atomically(&a.output, |w| {
        for py in 0..height {
            for px in 0..width {
                let ray = choice.view.ray((px as f64 + 0.5) / width as f64, (py as f64 + 0.5) / height as f64);
                w.write_all(bytemuck::bytes_of(&ray))?;
            }
        }
        Ok(())
    })
    .with_context(|| format!("cannot write rays file {}", a.output.display()))?;
    let summary = RaysSummary { output: &a.output, rays, width, height, view: view_name, bytes };
    if a.json {
        stdout_line(&serde_json::to_string(&summary)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "wrote {rays} rays ({width}×{height}, {view_name} view) to {}: {} ({bytes} bytes)",
            a.output.display(),
            human_bytes(bytes)
        ))?;
    }
    Ok(())
}
