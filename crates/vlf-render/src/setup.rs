//! Which camera and which lights a picture uses: the precedence rules of `vlf-bake render`, as
//! plain functions of values already parsed, so that the command line only parses and prints.
//!
//! **Camera** ([`choose_camera`]): the field's camera `N` if asked for by number; else a framing
//! if one is asked for; else a pinhole at a given eye point; else the field's first camera if it
//! has any; else a framing of the whole scene from outside ([`View::outside`]).
//!
//! **Size** ([`image_size`]): the width and height given; one of them alone, the other from the
//! aspect ratio of a field camera, else 4:3; neither, 640 pixels wide.
//!
//! **Lights** ([`choose_lights`]): the lights given by hand if any; else the field's own lights,
//! unless the defaults are asked for or it has none; else a key and a fill light around the camera
//! ([`default_lights`]).

use crate::light::{Light, default_lights};
use crate::math::{V3, cross, length, normalize, sub};
use crate::view::{SceneBounds, View};
use std::fmt;
use vlf_runtime::{CameraProjection, SceneCamera, SceneLight};

/// The image width when no size is given.
pub const DEFAULT_WIDTH: u32 = 640;
/// The image height when no size is given and no field camera has an aspect ratio.
pub const DEFAULT_HEIGHT: u32 = 480;
/// The largest image side [`image_size`] computes.
pub const MAX_SIDE: u32 = 65_535;

/// The image size for a `width` and a `height` each given or not, and the aspect ratio (`width /
/// height`) of the camera, if it has one: both given, as given; one, the other from the aspect
/// ratio (else 4:3), rounded, within 1 to [`MAX_SIDE`]; neither, [`DEFAULT_WIDTH`] wide.
pub fn image_size(width: Option<u32>, height: Option<u32>, aspect: Option<f64>) -> (u32, u32) {
    let aspect = aspect.filter(|r| r.is_finite() && *r > 0.0).unwrap_or(DEFAULT_WIDTH as f64 / DEFAULT_HEIGHT as f64);
    let side = |v: f64| (v.round().clamp(1.0, MAX_SIDE as f64)) as u32;
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, side(w as f64 / aspect)),
        (None, Some(h)) => (side(h as f64 * aspect), h),
        (None, None) => (DEFAULT_WIDTH, side(DEFAULT_WIDTH as f64 / aspect)),
    }
}

/// A framing of the scene's bounding sphere (the paper's two viewpoints).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Framing {
    /// From outside the sphere, framing all of it.
    Outside,
    /// From inside the scene, near its centre, looking across it.
    Inside,
}

/// The camera asked for: every field `None` means "not given".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRequest {
    /// Use the field's camera number `N` (0 = first).
    pub camera: Option<usize>,
    /// Frame the scene from outside or inside.
    pub framing: Option<Framing>,
    /// Place a pinhole camera here.
    pub eye: Option<V3>,
    /// The point an `eye` camera looks at (default: the centre of the scene).
    pub target: Option<V3>,
    /// The up direction of an `eye` camera.
    pub up: V3,
    /// The vertical field of view of an `eye` camera, in degrees.
    pub fov_degrees: f64,
    /// The image width in pixels.
    pub width: Option<u32>,
    /// The image height in pixels.
    pub height: Option<u32>,
}

/// The camera chosen, the image size that goes with it, and what it is, in words.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraChoice {
    pub view: View,
    pub width: u32,
    pub height: u32,
    /// `field camera 0 "name"`, `eye [..] looking at [..]`, `outside (framing the scene)`, ...
    pub description: String,
}

/// Why the camera asked for cannot be used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraError {
    /// The field has no camera with this number.
    NoSuchCamera { index: usize, count: usize },
    /// The field's camera has a degenerate frame.
    Degenerate { index: usize },
    /// An eye camera was asked to look at its own position.
    EyeIsTarget,
    /// An eye camera's up direction is zero or along its line of sight: it gives no image up.
    UpAlongSight,
    /// An eye camera's line of sight has no direction in f64: the eye and the target are so far
    /// apart that their distance overflows, or so close that it underflows to zero.
    SightOutOfRange {
        /// The distance from the eye to the target as f64 computes it (infinite or zero).
        distance: f64,
    },
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CameraError::NoSuchCamera { index, count } => write!(f, "camera {index}: the field has {count} camera(s)"),
            CameraError::Degenerate { index } => write!(f, "camera {index} cannot be used: its frame is degenerate"),
            CameraError::EyeIsTarget => write!(f, "the eye and the target are the same point"),
            CameraError::UpAlongSight => write!(f, "the up direction is zero or along the line of sight"),
            CameraError::SightOutOfRange { distance } => {
                write!(f, "the distance from the eye to the target ({distance:e}) gives the line of sight no direction")
            }
        }
    }
}

impl std::error::Error for CameraError {}

/// Chooses the camera for `request` (see the module documentation) among the field's `cameras`,
/// for the scene's `bounds`.
pub fn choose_camera(
    request: &CameraRequest,
    cameras: &[SceneCamera<'_>],
    bounds: &SceneBounds,
) -> Result<CameraChoice, CameraError> {
    let center = bounds.center;
    let field_camera = match (request.camera, request.framing, request.eye) {
        (Some(n), _, _) => Some(n),
        (None, None, None) if !cameras.is_empty() => Some(0),
        _ => None,
    };
    let chosen = field_camera
        .map(|n| cameras.get(n).map(|c| (n, c)).ok_or(CameraError::NoSuchCamera { index: n, count: cameras.len() }))
        .transpose()?;
    let camera_aspect = chosen.and_then(|(_, c)| match c.projection {
        CameraProjection::Perspective { aspect_ratio, .. } => aspect_ratio.map(f64::from),
        CameraProjection::Orthographic { xmag, ymag } => Some(xmag as f64 / ymag as f64),
    });
    let (width, height) = image_size(request.width, request.height, camera_aspect);
    let aspect = width as f64 / height as f64;
    let (view, description) = match (chosen, request.eye) {
        (Some((n, c)), _) => {
            let view = View::from_scene_camera(c, aspect).ok_or(CameraError::Degenerate { index: n })?;
            (view, format!("field camera {n} {:?}", c.name))
        }
        (None, Some(eye)) => {
            let target = request.target.unwrap_or(center);
            if eye == target {
                return Err(CameraError::EyeIsTarget);
            }
            let Some(sight) = normalize(sub(target, eye)) else {
                return Err(CameraError::SightOutOfRange { distance: length(sub(target, eye)) });
            };
            let across = normalize(request.up).map(|u| length(cross(sight, u)));
            if across.filter(|&a| a > 1e-9).is_none() {
                return Err(CameraError::UpAlongSight);
            }
            let view = View::look_at(eye, target, request.up, request.fov_degrees, aspect);
            (view, format!("eye {eye:?} looking at {target:?}"))
        }
        (None, None) => match request.framing.unwrap_or(Framing::Outside) {
            Framing::Outside => (View::outside(bounds, aspect), "outside (framing the scene)".to_string()),
            Framing::Inside => (View::inside(bounds, aspect), "inside (across the scene)".to_string()),
        },
    };
    Ok(CameraChoice { view, width, height, description })
}

/// The lights chosen, and where they came from, in words.
#[derive(Clone, Debug, PartialEq)]
pub struct LightChoice {
    pub lights: Vec<Light>,
    /// `from --light`, `the field's` or `default key and fill`.
    pub description: &'static str,
}

/// Chooses the lights (see the module documentation): `points` are white point lights
/// `[x, y, z, intensity]` given by hand, `field_lights` the field's, `defaults` asks for the key
/// and fill lights around `view` even if the field has lights.
pub fn choose_lights(
    points: &[[f64; 4]],
    defaults: bool,
    field_lights: &[SceneLight<'_>],
    view: &View,
    center: V3,
    radius: f64,
) -> LightChoice {
    let field_lights: Vec<Light> = field_lights.iter().filter_map(Light::from_scene_light).collect();
    let (lights, description) = if !points.is_empty() {
        (points.iter().map(|l| Light::point([l[0], l[1], l[2]], l[3])).collect(), "from --light")
    } else if !field_lights.is_empty() && !defaults {
        (field_lights, "the field's")
    } else {
        (default_lights(view, center, radius), "default key and fill")
    };
    LightChoice { lights, description }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vlf_runtime::LightKind;

    const CENTER: V3 = [0.0, 1.0, 0.0];
    const RADIUS: f64 = 2.0;
    const BOUNDS: SceneBounds =
        SceneBounds { center: CENTER, radius: RADIUS, min: [-1.0, 0.0, -1.0], max: [1.0, 2.0, 1.0] };

    fn request() -> CameraRequest {
        CameraRequest {
            camera: None,
            framing: None,
            eye: None,
            target: None,
            up: [0.0, 1.0, 0.0],
            fov_degrees: 50.0,
            width: Some(640),
            height: None,
        }
    }

    fn camera(name: &str, projection: CameraProjection) -> SceneCamera<'_> {
        SceneCamera {
            name,
            projection,
            position: [0.0, 1.0, 5.0],
            forward: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            znear: 0.1,
            zfar: None,
            input: 0,
            camera: 0,
            node: 0,
        }
    }

    fn perspective(aspect_ratio: Option<f32>) -> CameraProjection {
        CameraProjection::Perspective { yfov: 0.8, aspect_ratio }
    }

    #[test]
    fn without_flags_the_fields_first_camera_is_used_and_sets_the_height() {
        let cameras = [camera("front", perspective(Some(2.0))), camera("back", perspective(None))];
        let c = choose_camera(&request(), &cameras, &BOUNDS).unwrap();
        assert_eq!(c.description, "field camera 0 \"front\"");
        assert_eq!(c.height, 320, "640 wide at the camera's aspect ratio of 2");
        assert_eq!(c.view, View::from_scene_camera(&cameras[0], 2.0).unwrap());
        // An orthographic camera's aspect is xmag / ymag; a given height wins.
        let ortho = [camera("plan", CameraProjection::Orthographic { xmag: 4.0, ymag: 1.0 })];
        assert_eq!(choose_camera(&request(), &ortho, &BOUNDS).unwrap().height, 160);
        let given = CameraRequest { height: Some(100), ..request() };
        assert_eq!(choose_camera(&given, &ortho, &BOUNDS).unwrap().height, 100);
    }

    #[test]
    fn a_camera_number_picks_that_camera_and_a_missing_one_is_an_error() {
        let cameras = [camera("front", perspective(None)), camera("back", perspective(None))];
        let second = CameraRequest { camera: Some(1), ..request() };
        let c = choose_camera(&second, &cameras, &BOUNDS).unwrap();
        assert_eq!(c.description, "field camera 1 \"back\"");
        assert_eq!(c.height, DEFAULT_HEIGHT, "no aspect ratio in the camera: the default height");
        let third = CameraRequest { camera: Some(2), ..request() };
        assert_eq!(choose_camera(&third, &cameras, &BOUNDS), Err(CameraError::NoSuchCamera { index: 2, count: 2 }));
        let mut flat = camera("flat", perspective(None));
        flat.forward = [0.0; 3];
        assert_eq!(choose_camera(&request(), &[flat], &BOUNDS), Err(CameraError::Degenerate { index: 0 }));
    }

    #[test]
    fn a_framing_or_an_eye_overrides_the_fields_cameras() {
        let cameras = [camera("front", perspective(Some(2.0)))];
        let inside = CameraRequest { framing: Some(Framing::Inside), ..request() };
        let c = choose_camera(&inside, &cameras, &BOUNDS).unwrap();
        assert_eq!(c.description, "inside (across the scene)");
        assert_eq!(c.height, DEFAULT_HEIGHT);
        assert_eq!(c.view, View::inside(&BOUNDS, 640.0 / 480.0));

        let eye = CameraRequest { eye: Some([3.0, 1.0, 0.0]), ..request() };
        let c = choose_camera(&eye, &cameras, &BOUNDS).unwrap();
        assert_eq!(
            c.description, "eye [3.0, 1.0, 0.0] looking at [0.0, 1.0, 0.0]",
            "the target defaults to the centre"
        );
        assert_eq!(c.view, View::look_at([3.0, 1.0, 0.0], CENTER, [0.0, 1.0, 0.0], 50.0, 640.0 / 480.0));
        let same = CameraRequest { eye: Some(CENTER), ..request() };
        assert_eq!(choose_camera(&same, &cameras, &BOUNDS), Err(CameraError::EyeIsTarget));
        // An up direction along the line of sight (either way) gives no image up.
        for up in [[0.0, 1.0, 0.0], [0.0, -3.0, 0.0], [0.0, 0.0, 0.0]] {
            let above = CameraRequest { eye: Some([0.0, 9.0, 0.0]), up, ..request() };
            assert_eq!(choose_camera(&above, &cameras, &BOUNDS), Err(CameraError::UpAlongSight), "{up:?}");
        }
        // An eye so far from (or so near) the target that the line of sight overflows (or
        // underflows) is named for that, not for its up direction.
        for (eye, target) in [([1e308, 0.0, 0.0], [-1e308, 0.0, 0.0]), ([1e-300, 0.0, 0.0], [0.0; 3])] {
            let far = CameraRequest { eye: Some(eye), target: Some(target), ..request() };
            assert!(
                matches!(choose_camera(&far, &cameras, &BOUNDS), Err(CameraError::SightOutOfRange { .. })),
                "{eye:?}"
            );
        }
        let tilted = CameraRequest { eye: Some([0.0, 9.0, 0.0]), up: [0.0, 0.0, -1.0], ..request() };
        assert!(choose_camera(&tilted, &cameras, &BOUNDS).is_ok());
    }

    #[test]
    fn one_size_keeps_the_aspect_ratio_and_none_gives_640_by_480() {
        let four_by_three = None;
        assert_eq!(image_size(None, None, four_by_three), (640, 480));
        assert_eq!(image_size(Some(800), None, four_by_three), (800, 600));
        assert_eq!(image_size(None, Some(300), four_by_three), (400, 300));
        assert_eq!(image_size(Some(100), Some(700), four_by_three), (100, 700));
        assert_eq!(image_size(None, Some(300), Some(2.0)), (600, 300));
        assert_eq!(image_size(Some(48), None, Some(f64::NAN)), (48, 36));
        assert_eq!(image_size(Some(65_535), None, Some(1e-9)), (65_535, MAX_SIDE));
        assert_eq!(image_size(None, Some(1), Some(1e-9)), (1, 1));
        let wide = CameraRequest { width: None, height: Some(300), ..request() };
        let c = choose_camera(&wide, &[], &BOUNDS).unwrap();
        assert_eq!((c.width, c.height), (400, 300));
    }

    #[test]
    fn without_cameras_or_flags_the_scene_is_framed_from_outside() {
        let c = choose_camera(&request(), &[], &BOUNDS).unwrap();
        assert_eq!(c.description, "outside (framing the scene)");
        assert_eq!(c.view, View::outside(&BOUNDS, 640.0 / 480.0));
    }

    #[test]
    fn lights_by_hand_win_then_the_fields_then_the_defaults() {
        let view = View::outside(&BOUNDS, 1.0);
        let lamp = SceneLight {
            name: "lamp",
            kind: LightKind::Point,
            position: [0.0, 3.0, 0.0],
            direction: [0.0, -1.0, 0.0],
            color: [1.0; 3],
            intensity: 10.0,
            range: None,
            input: 0,
            light: 0,
            node: 0,
        };
        let by_hand = choose_lights(&[[1.0, 2.0, 3.0, 4.0]], false, &[lamp], &view, CENTER, RADIUS);
        assert_eq!(by_hand.description, "from --light");
        assert_eq!(by_hand.lights, [Light::point([1.0, 2.0, 3.0], 4.0)]);
        let own = choose_lights(&[], false, &[lamp], &view, CENTER, RADIUS);
        assert_eq!((own.description, own.lights.len()), ("the field's", 1));
        assert_eq!(own.lights, [Light::from_scene_light(&lamp).unwrap()]);
        let defaults = default_lights(&view, CENTER, RADIUS);
        for chosen in [
            choose_lights(&[], true, &[lamp], &view, CENTER, RADIUS),
            choose_lights(&[], false, &[], &view, CENTER, RADIUS),
        ] {
            assert_eq!(chosen.description, "default key and fill");
            assert_eq!(chosen.lights, defaults);
        }
    }
}
