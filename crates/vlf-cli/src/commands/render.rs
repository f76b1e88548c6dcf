//! `vlf-bake render`: Whitted ray tracing of a field into a PNG, and optionally a picture of the
//! work per pixel (`--scene`: of a scene file, [`super::scene`]).

use super::picture::{setup, summarise};
use crate::args::RenderArgs;
use crate::distinct::{Writes, check_outputs};
use crate::progress::Bar;
use crate::values::BadUsage;
use anyhow::{Context, Result};
use std::io::Write;
use std::time::Instant;
use vlf_bake::Progress;
use vlf_bake::atomic::write_atomically;
use vlf_render::{Scene, SceneBounds, SceneOptions};

/// `vlf-bake render`: ray traces a picture of a field (and of its work) and prints the summary.
pub fn run(a: &RenderArgs) -> Result<()> {
    // Every flag's range was checked as it was parsed (`crate::values`).
    let source = a.field.as_deref().map(|f| ("FIELD", f)).or(a.scene.as_deref().map(|s| ("--scene", s)));
    let work = a.work_image.as_deref().map(|w| ("--work-image", w));
    check_outputs(
        source.as_slice(),
        &[[("-o/--output", a.output.as_path())].as_slice(), work.as_slice()].concat(),
        Writes::Through,
    )?;
    let Some(path) = &a.field else { return super::scene::render(a) };
    // (clap does not enforce `requires` against an argument that conflicts with one present.)
    if a.frames.is_some() || !a.moves.is_empty() || a.path.is_some() {
        return Err(
            BadUsage("--frames, --move and --path need --scene: a field alone has nothing to move".into()).into()
        );
    }
    let field = super::open_field(path)?;
    let bounds = SceneBounds::of(&field);
    let cameras: Vec<_> = field.cameras().collect();
    let field_lights: Vec<_> = field.lights().collect();
    let s = setup(a, &cameras, &field_lights, &bounds, &path.display().to_string(), 1)?;
    let options = SceneOptions { smooth: !a.flat, ..SceneOptions::default() };
    let scene = Scene::from_field(&field, &options);
    let bar = Bar::new(a.quiet || a.json);
    bar.begin("rendering rows", s.settings.height as u64);
    let start = Instant::now();
    let frame = vlf_render::render(field.view(), &scene, &s.view, &s.lights, &s.settings, &|rows| bar.advance(rows));
    let seconds = start.elapsed().as_secs_f64();
    bar.end();
    let png = vlf_render::encode_png(frame.width, frame.height, &vlf_render::to_srgb8(&frame, a.exposure))?;
    write_atomically(&a.output, |w| w.write_all(&png))
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    summarise(a, &s, &frame, None, seconds)
}
