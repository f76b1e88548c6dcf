//! Point, spot and directional lights: from the field's glTF lights (`KHR_lights_punctual`
//! units and falloff), from flags, or a default key and fill placed around the camera.

use crate::math::{V3, dot, length, madd, normalize, scale, sub, widen};
use crate::view::View;
use vlf_runtime::{LightKind, SceneLight};

/// Where a light is and how it spreads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// From a point in every direction.
    Point { position: V3 },
    /// From a point within a cone around the unit `direction` (the direction light travels):
    /// full strength inside `cos_inner`, none outside `cos_outer`.
    Spot { position: V3, direction: V3, cos_inner: f64, cos_outer: f64 },
    /// Parallel light travelling along the unit `direction`.
    Directional { direction: V3 },
}

/// A light: an emitter and its radiant strength per colour channel (colour times intensity; for
/// point and spot lights the irradiance at distance `d` is `strength / d²`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub emitter: Emitter,
    pub strength: V3,
    /// Distance beyond which the light has no effect (glTF's smooth cut-off); `None` = unlimited.
    pub range: Option<f64>,
}

/// What a light contributes at a point.
pub(crate) struct Incident {
    /// Unit direction from the point towards the light.
    pub to_light: V3,
    /// Distance to the light (infinite for directional lights).
    pub distance: f64,
    pub irradiance: V3,
}

impl Light {
    /// A white point light of strength `intensity` (irradiance `intensity / d²`).
    pub fn point(position: V3, intensity: f64) -> Light {
        Light { emitter: Emitter::Point { position }, strength: [intensity; 3], range: None }
    }

    /// The renderer's light for a field's light, or `None` if it holds values no light can have
    /// (a damaged field).
    pub fn from_scene_light(l: &SceneLight<'_>) -> Option<Light> {
        let position = widen(l.position);
        let strength = scale(widen(l.color), l.intensity as f64);
        if !position.iter().chain(&strength).all(|v| v.is_finite()) || strength.iter().any(|&s| s < 0.0) {
            return None;
        }
        let range = l.range.map(f64::from).filter(|r| r.is_finite() && *r > 0.0);
        let emitter = match l.kind {
            LightKind::Point => Emitter::Point { position },
            LightKind::Spot { inner_cone, outer_cone } => {
                let (inner, outer) = (inner_cone as f64, outer_cone as f64);
                if !(inner >= 0.0 && inner < outer && outer <= std::f64::consts::FRAC_PI_2) {
                    return None;
                }
                let direction = normalize(widen(l.direction))?;
                Emitter::Spot { position, direction, cos_inner: inner.cos(), cos_outer: outer.cos() }
            }
            LightKind::Directional => Emitter::Directional { direction: normalize(widen(l.direction))? },
        };
        Some(Light { emitter, strength, range })
    }

    /// The light with its position given relative to `origin` (the frame [`crate::render`]
    /// traces in); the light itself when `origin` is zero.
    pub(crate) fn relative_to(&self, origin: V3) -> Light {
        let emitter = match self.emitter {
            Emitter::Point { position } => Emitter::Point { position: sub(position, origin) },
            Emitter::Spot { position, direction, cos_inner, cos_outer } => {
                Emitter::Spot { position: sub(position, origin), direction, cos_inner, cos_outer }
            }
            directional @ Emitter::Directional { .. } => directional,
        };
        Light { emitter, ..*self }
    }

    /// The light arriving at `p`, or `None` if none does (outside a spot's cone, beyond range).
    pub(crate) fn incident(&self, p: V3) -> Option<Incident> {
        let (position, cone) = match self.emitter {
            Emitter::Directional { direction } => {
                return Some(Incident {
                    to_light: scale(direction, -1.0),
                    distance: f64::INFINITY,
                    irradiance: self.strength,
                });
            }
            Emitter::Point { position } => (position, None),
            Emitter::Spot { position, direction, cos_inner, cos_outer } => {
                (position, Some((direction, cos_inner, cos_outer)))
            }
        };
        let offset = sub(position, p);
        let distance = length(offset);
        let to_light = normalize(offset)?;
        let mut factor = 1.0 / (distance * distance);
        if let Some(range) = self.range {
            // KHR_lights_punctual's recommended window: smooth, zero at `range`.
            let x = (distance / range).powi(4);
            factor *= (1.0 - x).clamp(0.0, 1.0).powi(2);
        }
        if let Some((direction, cos_inner, cos_outer)) = cone {
            let cos = -dot(to_light, direction);
            let t = ((cos - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
            factor *= t * t;
        }
        (factor > 0.0 && factor.is_finite()).then(|| Incident {
            to_light,
            distance,
            irradiance: scale(self.strength, factor),
        })
    }
}

/// A key light above and to the left of the camera and a dimmer fill to its right, so that any
/// scene is lit from the side it is seen from. The lights sit at the scale of the view's reach:
/// the distance to the centre of the scene's bounding sphere (`center`, `radius`) from outside it,
/// a fifth of its radius from inside (close to the eye, where little stands in the way). Strengths give an irradiance of about 1 (key) and 0.3 (fill) at
/// that distance in front of the camera.
pub fn default_lights(view: &View, center: V3, radius: f64) -> Vec<Light> {
    let to_center = length(sub(center, view.eye));
    let reach = if to_center > radius { to_center } else { 0.2 * radius };
    let target = madd(view.eye, view.forward, reach);
    let place = |right: f64, up: f64, back: f64| {
        madd(madd(madd(view.eye, view.right, right * reach), view.up, up * reach), view.forward, -back * reach)
    };
    // Close enough to the camera to reach what it sees through an opening (a room seen through
    // its open side), far enough to model shapes.
    let key = place(-0.4, 0.3, 0.0);
    let fill = place(0.5, -0.05, 0.0);
    let strength = |p: V3, irradiance: f64| {
        let d = length(sub(target, p));
        irradiance * d * d
    };
    vec![
        Light {
            emitter: Emitter::Point { position: key },
            strength: scale([1.0, 0.97, 0.92], strength(key, 1.0)),
            range: None,
        },
        Light {
            emitter: Emitter::Point { position: fill },
            strength: scale([0.85, 0.9, 1.0], strength(fill, 0.3)),
            range: None,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn irradiance(light: &Light, p: V3) -> f64 {
        light.incident(p).map_or(0.0, |i| i.irradiance[0])
    }

    #[test]
    fn point_lights_fall_off_with_the_square_of_the_distance_and_stop_at_their_range() {
        let mut light = Light::point([0.0, 0.0, 0.0], 8.0);
        assert_eq!(irradiance(&light, [2.0, 0.0, 0.0]), 2.0);
        assert_eq!(irradiance(&light, [0.0, 0.0, -4.0]), 0.5);
        light.range = Some(3.0);
        assert!(irradiance(&light, [2.0, 0.0, 0.0]) < 2.0 && irradiance(&light, [2.0, 0.0, 0.0]) > 0.0);
        assert_eq!(irradiance(&light, [3.5, 0.0, 0.0]), 0.0);
    }

    #[test]
    fn spot_lights_are_full_inside_the_inner_cone_and_dark_outside_the_outer() {
        let light = Light {
            emitter: Emitter::Spot {
                position: [0.0; 3],
                direction: [0.0, -1.0, 0.0],
                cos_inner: 20f64.to_radians().cos(),
                cos_outer: 40f64.to_radians().cos(),
            },
            strength: [1.0; 3],
            range: None,
        };
        let at = |degrees: f64| {
            let a = degrees.to_radians();
            irradiance(&light, [a.sin(), -a.cos(), 0.0])
        };
        assert!((at(10.0) - 1.0).abs() < 1e-12);
        assert!(at(30.0) > 0.0 && at(30.0) < 1.0);
        assert_eq!(at(45.0), 0.0);
        let sun =
            Light { emitter: Emitter::Directional { direction: [0.0, -1.0, 0.0] }, strength: [3.0; 3], range: None };
        let i = sun.incident([5.0, 5.0, 5.0]).unwrap();
        assert_eq!((i.to_light, i.distance, i.irradiance), ([0.0, 1.0, 0.0], f64::INFINITY, [3.0; 3]));
    }
}
