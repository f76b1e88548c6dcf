//! What a field carries for rendering besides geometry (`formats/vlf.md` §5.10–5.12, format 1.1):
//! materials, reached from a triangle through its provenance, and the cameras and punctual lights
//! of glTF inputs. Read from the mapped sections like everything else; a value a lying file holds
//! is returned as it is (callers that need finite numbers check), never a panic.

use vlf_format::{CameraRecord, FieldReader, LightRecord, MaterialRecord, NO_INDEX, camera_kind, light_kind};

/// A surface of classical (Whitted) ray tracing, as MATERIALS stores it. Colours are linear RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material<'a> {
    /// The material's name in its input (may be empty).
    pub name: &'a str,
    /// The input (index into the field's inputs) whose material list holds it.
    pub input: u32,
    /// Its index in that list: OBJ, the position in the `.mtl` libraries; glTF, the material index.
    pub index: u32,
    /// Lambert reflectance.
    pub diffuse: [f32; 3],
    /// Phong exponent.
    pub shininess: f32,
    /// Colour of Phong highlights.
    pub specular: [f32; 3],
    /// Index of refraction of the inside (1 = rays pass unbent).
    pub ior: f32,
    /// Weight of the mirror-reflected ray.
    pub reflection: [f32; 3],
    /// Weight of the refracted ray.
    pub transmission: [f32; 3],
    /// Light the surface emits.
    pub emission: [f32; 3],
}

/// How a camera projects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraProjection {
    /// A pinhole: vertical field of view in radians, and width / height if the file gives one.
    Perspective {
        /// Vertical field of view in radians, in `(0, π)`.
        yfov: f32,
        /// Width / height, if the file gives one.
        aspect_ratio: Option<f32>,
    },
    /// Parallel rays: half the view's width and height in world units.
    Orthographic {
        /// Half the view's width, in world units.
        xmag: f32,
        /// Half the view's height, in world units.
        ymag: f32,
    },
}

/// A camera placed in the scene by a glTF node (CAMERAS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneCamera<'a> {
    /// The camera's name, else its node's (may be empty).
    pub name: &'a str,
    /// Perspective or orthographic, with its parameters.
    pub projection: CameraProjection,
    /// World-space eye point.
    pub position: [f32; 3],
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Unit up direction, orthogonal to `forward`.
    pub up: [f32; 3],
    /// Near plane distance, ≥ 0.
    pub znear: f32,
    /// `None` = infinite.
    pub zfar: Option<f32>,
    /// The input (index into the field's inputs) it came from.
    pub input: u32,
    /// Its glTF camera index in that input.
    pub camera: u32,
    /// The glTF node that places it.
    pub node: u32,
}

/// The kind of a punctual light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Emits from `position` in all directions; intensity in candela.
    Point,
    /// Emits from `position` in a cone around `direction`: full intensity (candela) within
    /// `inner_cone` radians, fading to zero at `outer_cone`.
    Spot {
        /// Half-angle of full intensity, in radians.
        inner_cone: f32,
        /// Half-angle where the intensity reaches zero, in radians.
        outer_cone: f32,
    },
    /// Parallel light travelling along `direction`; intensity in lux.
    Directional,
}

/// A `KHR_lights_punctual` light placed by a glTF node (LIGHTS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneLight<'a> {
    /// The light's name, else its node's (may be empty).
    pub name: &'a str,
    /// Point, spot (with its cone) or directional.
    pub kind: LightKind,
    /// World-space position (point and spot lights).
    pub position: [f32; 3],
    /// Unit direction the light travels (spot and directional lights).
    pub direction: [f32; 3],
    /// Linear RGB.
    pub color: [f32; 3],
    /// Candela for point and spot lights, lux for directional lights.
    pub intensity: f32,
    /// Distance beyond which the light has no effect; `None` = unlimited.
    pub range: Option<f32>,
    /// The input (index into the field's inputs) it came from.
    pub input: u32,
    /// Its `KHR_lights_punctual` light index in that input.
    pub light: u32,
    /// The glTF node that places it.
    pub node: u32,
}

/// The rendering sections of a field's reader, read as the types above (the methods of
/// [`crate::Field`] of the same names delegate here).
#[derive(Clone, Copy)]
pub(crate) struct SceneSections<'a>(pub(crate) FieldReader<'a>);

impl<'a> SceneSections<'a> {
    /// Every material the field holds, in MATERIALS order (sorted by input, then index).
    pub(crate) fn materials(self) -> impl ExactSizeIterator<Item = Material<'a>> {
        self.0.materials.iter().map(move |m| self.material_from(m))
    }

    /// The position in [`crate::Field::materials`] of the material of triangle `prim`: its source's
    /// material, looked up by (input, index) with a binary search. `None` if the triangle has no
    /// material or the field holds no record for it (a 1.0 field holds none): use a default.
    pub(crate) fn material_index(self, prim: u32) -> Option<usize> {
        let r = self.0;
        let source = r.sources.get(r.provenance.get(prim as usize)?.source as usize)?;
        if source.material == NO_INDEX {
            return None;
        }
        r.materials.binary_search_by_key(&(source.input, source.material), |m| (m.input, m.index)).ok()
    }

    /// The material of triangle `prim` ([`crate::Field::material_index`]).
    pub(crate) fn material(self, prim: u32) -> Option<Material<'a>> {
        self.material_index(prim).map(|i| self.material_from(&self.0.materials[i]))
    }

    /// The cameras of the field's glTF inputs, in node order. A record of an unknown kind (a
    /// newer or damaged file) is skipped.
    pub(crate) fn cameras(self) -> impl Iterator<Item = SceneCamera<'a>> {
        self.0.cameras.iter().filter_map(move |c| self.camera_from(c))
    }

    /// The punctual lights of the field's glTF inputs, in node order. A record of an unknown kind
    /// is skipped.
    pub(crate) fn lights(self) -> impl Iterator<Item = SceneLight<'a>> {
        self.0.lights.iter().filter_map(move |l| self.light_from(l))
    }

    fn name(self, offset: u32, length: u32) -> &'a str {
        self.0.string(offset, length).unwrap_or("")
    }

    fn material_from(self, m: &MaterialRecord) -> Material<'a> {
        Material {
            name: self.name(m.name_offset, m.name_length),
            input: m.input,
            index: m.index,
            diffuse: m.diffuse,
            shininess: m.shininess,
            specular: m.specular,
            ior: m.ior,
            reflection: m.reflection,
            transmission: m.transmission,
            emission: m.emission,
        }
    }

    fn camera_from(self, c: &CameraRecord) -> Option<SceneCamera<'a>> {
        let projection = match c.kind {
            camera_kind::PERSPECTIVE => CameraProjection::Perspective {
                yfov: c.yfov,
                aspect_ratio: (c.aspect_ratio > 0.0).then_some(c.aspect_ratio),
            },
            camera_kind::ORTHOGRAPHIC => CameraProjection::Orthographic { xmag: c.xmag, ymag: c.ymag },
            _ => return None,
        };
        Some(SceneCamera {
            name: self.name(c.name_offset, c.name_length),
            projection,
            position: c.position,
            forward: c.forward,
            up: c.up,
            znear: c.znear,
            zfar: (c.zfar > 0.0).then_some(c.zfar),
            input: c.input,
            camera: c.camera,
            node: c.node,
        })
    }

    fn light_from(self, l: &LightRecord) -> Option<SceneLight<'a>> {
        let kind = match l.kind {
            light_kind::POINT => LightKind::Point,
            light_kind::SPOT => LightKind::Spot { inner_cone: l.inner_cone, outer_cone: l.outer_cone },
            light_kind::DIRECTIONAL => LightKind::Directional,
            _ => return None,
        };
        Some(SceneLight {
            name: self.name(l.name_offset, l.name_length),
            kind,
            position: l.position,
            direction: l.direction,
            color: l.color,
            intensity: l.intensity,
            range: (l.range > 0.0).then_some(l.range),
            input: l.input,
            light: l.light,
            node: l.node,
        })
    }
}
