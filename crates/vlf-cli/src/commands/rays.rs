//! `vlf-bake rays`: a rays file of primary rays for a camera that frames a field's scene.

use crate::args::{RaysArgs, View};
use anyhow::{Context, Result, bail};
use std::io::Write;
use vlf_bake::atomic::write_atomically;
use vlf_runtime::Field;

/// `vlf-bake rays`: writes the primary rays of a camera framing the field's scene.
pub fn run(a: &RaysArgs) -> Result<()> {
    if a.width == 0 || a.height == 0 {
        bail!("--width and --height must be positive");
    }
    let field = Field::open(&a.field)?;
    let (center, radius) = field.bounding_sphere();
    let aspect = a.width as f64 / a.height as f64;
    let camera = match a.view {
        View::Outside => vlf_geom::Camera::outside(center, radius, aspect),
        View::Inside => vlf_geom::Camera::inside(center, radius, aspect),
    };
    let rays = camera.primary_rays(a.width, a.height);
    write_atomically(&a.output, |w| w.write_all(bytemuck::cast_slice(&rays)))
        .with_context(|| format!("cannot write rays file {}", a.output.display()))?;
    Ok(())
}
