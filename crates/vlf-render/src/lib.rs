//! Turn ray queries into pictures: classical (Whitted) ray tracing of a VLF field, as the paper
//! frames its method (Mortensen et al., §1: "'classical' ray tracing as described by Whitted").
//!
//! - [`Scene`]: a field's triangles, smoothed shading normals and surfaces ([`Surface`], from the
//!   materials the field carries, `formats/vlf.md` §5.10, else a default);
//!   [`Scene::from_instances`] shades a dynamic scene of `vlf_scene` instances;
//! - [`View`]: a pinhole or orthographic camera: framing the scene from outside or inside (the
//!   paper's viewpoints), placed by hand, or a glTF camera from the field;
//! - [`Light`]: point, spot and directional lights: the field's glTF lights, or
//!   [`default_lights`] around the camera;
//! - [`render`]: primary rays, shadow rays through any-hit queries, mirror reflection and
//!   refraction to a depth limit, Lambert and Phong shading, on all cores, over any
//!   [`vlf_geom::Intersector`] (the field, the kd-tree baseline, brute force), counting the work
//!   per pixel;
//! - [`to_srgb8`], [`work_image`] and [`encode_png`]: the picture, a false-colour picture of where
//!   the work went, and PNG bytes.
//!
//! ```no_run
//! use vlf_render::*;
//! use vlf_runtime::Field;
//!
//! let field = Field::open("scene.vlf")?;
//! let scene = Scene::from_field(&field, &SceneOptions::default());
//! let settings = Settings::default();
//! let bounds = SceneBounds::of(&field);
//! let view = View::outside(&bounds, settings.width as f64 / settings.height as f64);
//! let lights = default_lights(&view, bounds.center, bounds.radius);
//! let frame = render(&field, &scene, &view, &lights, &settings, &|_| {});
//! let png = encode_png(frame.width, frame.height, &to_srgb8(&frame, 1.0))?;
//! std::fs::write("scene.png", png)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Textures are out of scope: a field's materials are constant colours.

#![forbid(unsafe_code)]

mod framing;
mod image;
mod instances;
mod light;
mod math;
mod render;
mod scene;
pub mod setup;
mod view;

pub use image::{
    WorkImage, WorkMetric, decode_png, encode_apng, encode_png, inferno, picture_bytes_at_most, to_srgb8, work_image,
};
pub use light::{Emitter, Light, default_lights};
pub use math::V3;
pub use render::{Background, Frame, MAX_BOUNCES, RayCounts, Settings, render};
pub use scene::{Scene, SceneOptions, Surface};
pub use view::{MIN_F32_STEPS, SceneBounds, View};
