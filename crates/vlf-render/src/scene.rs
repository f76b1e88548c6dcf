//! What the renderer shades with: the triangles, their shading normals and their surfaces, taken
//! from a field (`formats/vlf.md` §5.10 for materials).

use crate::math::{V3, cross, dot, normalize, sub, widen};
use vlf_runtime::{Field, Material};

/// A surface of the Whitted model in the renderer's terms: linear RGB weights, sanitised so that
/// shading never meets a NaN, a negative weight or an index of refraction that is not positive
/// (whatever a damaged file holds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Lambert reflectance.
    pub diffuse: V3,
    /// Phong highlight colour and exponent.
    pub specular: V3,
    pub shininess: f64,
    /// Weight of the mirror-reflected ray.
    pub reflection: V3,
    /// Weight of the refracted ray (split with the reflected one by Fresnel's law).
    pub transmission: V3,
    /// Light the surface emits.
    pub emission: V3,
    /// Index of refraction of the inside.
    pub ior: f64,
}

impl Surface {
    /// The surface of a triangle without a material: a light warm grey with a soft highlight.
    pub const DEFAULT: Surface = Surface {
        diffuse: [0.72, 0.70, 0.66],
        specular: [0.12, 0.12, 0.12],
        shininess: 48.0,
        reflection: [0.0; 3],
        transmission: [0.0; 3],
        emission: [0.0; 3],
        ior: 1.0,
    };

    /// The surface of a field's material, sanitised.
    pub fn from_material(m: &Material<'_>) -> Surface {
        let colour = |c: [f32; 3]| widen(c).map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
        let shininess = m.shininess as f64;
        let ior = m.ior as f64;
        Surface {
            diffuse: colour(m.diffuse),
            specular: colour(m.specular),
            shininess: if shininess.is_finite() { shininess.clamp(0.0, 1e4) } else { 1.0 },
            reflection: colour(m.reflection),
            transmission: colour(m.transmission),
            emission: colour(m.emission),
            ior: if ior.is_finite() && ior > 0.0 { ior } else { 1.0 },
        }
    }
}

/// Options for [`Scene::from_field`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneOptions {
    /// Interpolate vertex normals across edges whose faces meet at less than `crease_degrees`
    /// (a field stores no normals: they are averaged from the faces that share each vertex).
    pub smooth: bool,
    pub crease_degrees: f64,
}

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions { smooth: true, crease_degrees: 40.0 }
    }
}

/// Vertices shared by more triangles than this keep flat normals: averaging costs the square of
/// the count.
const MAX_SMOOTHING_VALENCE: usize = 256;

/// The geometry and surfaces a frame is shaded with.
#[derive(Clone, Debug)]
pub struct Scene {
    triangles: Vec<[[f32; 3]; 3]>,
    /// The point `triangles` are relative to, world coordinates.
    origin: V3,
    /// Unit shading normals per corner, or `None` for flat shading.
    normals: Option<Vec<[[f32; 3]; 3]>>,
    /// Index into `surfaces` of each triangle's surface.
    surface_of: Vec<u32>,
    surfaces: Vec<Surface>,
    center: V3,
    radius: f64,
}

/// Everything shading needs to know about a hit.
pub(crate) struct SurfacePoint {
    pub point: V3,
    /// Unit geometric normal as the triangle is wound (counter-clockwise = front).
    pub wound_normal: V3,
    /// Unit shading normal, on the same side as `wound_normal`.
    pub shading_normal: V3,
    pub surface: Surface,
}

impl Scene {
    /// The scene of a field: its triangles, each with the surface of its material
    /// ([`Field::material`]) or [`Surface::DEFAULT`].
    pub fn from_field(field: &Field, options: &SceneOptions) -> Scene {
        let count = field.triangle_count();
        let triangles: Vec<[[f32; 3]; 3]> = (0..count).map(|i| field.triangle_local(i).unwrap_or_default()).collect();
        let mut surfaces: Vec<Surface> = field.materials().map(|m| Surface::from_material(&m)).collect();
        let default = surfaces.len() as u32;
        surfaces.push(Surface::DEFAULT);
        let surface_of = (0..count).map(|i| field.material_index(i).map_or(default, |m| m as u32)).collect();
        let (center, radius) = field.bounding_sphere();
        Scene::new(triangles, field.origin(), surfaces, surface_of, center, radius, options)
    }

    /// A scene from parts: `triangles` relative to `origin` (as a field stores them),
    /// `surface_of[i]` indexes `surfaces` (an index out of range gets [`Surface::DEFAULT`]);
    /// `center` and `radius` bound the triangles in world coordinates.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        triangles: Vec<[[f32; 3]; 3]>,
        origin: V3,
        mut surfaces: Vec<Surface>,
        mut surface_of: Vec<u32>,
        center: V3,
        radius: f64,
        options: &SceneOptions,
    ) -> Scene {
        let default = surfaces.len() as u32;
        surfaces.push(Surface::DEFAULT);
        surface_of.resize(triangles.len(), default);
        for s in &mut surface_of {
            if *s > default {
                *s = default;
            }
        }
        let normals = options.smooth.then(|| smooth_normals(&triangles, options.crease_degrees));
        Scene { triangles, origin, normals, surface_of, surfaces, center, radius }
    }

    /// The triangles, by id, relative to [`Scene::origin`] (to build another acceleration
    /// structure over the same scene, e.g. `BruteForce::relative(scene.triangles(), scene.origin())`).
    pub fn triangles(&self) -> &[[[f32; 3]; 3]] {
        &self.triangles
    }

    /// The point the triangles are relative to, in world coordinates.
    pub fn origin(&self) -> V3 {
        self.origin
    }

    /// Centre and radius of a sphere around the scene.
    pub fn bounding_sphere(&self) -> (V3, f64) {
        (self.center, self.radius)
    }

    /// A distance small against the scene, large against f32 rounding of its coordinates relative
    /// to `frame` (the point rays are given relative to): how far secondary rays start off their
    /// surface. The coordinates are at most the radius plus the centre's distance from `frame`.
    pub(crate) fn epsilon(&self, frame: V3) -> f64 {
        let magnitude = self.radius + (0..3).fold(0.0f64, |m, i| m.max((self.center[i] - frame[i]).abs()));
        1e-5 * magnitude
    }

    /// The hit point of triangle `prim` at barycentrics `(u, v)`, relative to `frame` (the point
    /// rays are given relative to: exact in the triangles' own frame, [`Scene::origin`]), or
    /// `None` for an id the scene does not have (a damaged field).
    pub(crate) fn surface_point(&self, prim: u32, u: f32, v: f32, frame: V3) -> Option<SurfacePoint> {
        let t = self.triangles.get(prim as usize)?;
        let [a, b, c] = t.map(widen);
        let (u, v) = (u as f64, v as f64);
        let w = 1.0 - u - v;
        let shift = sub(self.origin, frame);
        let point: V3 = std::array::from_fn(|i| shift[i] + (w * a[i] + u * b[i] + v * c[i]));
        let e1: V3 = std::array::from_fn(|i| b[i] - a[i]);
        let e2: V3 = std::array::from_fn(|i| c[i] - a[i]);
        let wound_normal = normalize(cross(e1, e2))?;
        let shading_normal = self
            .normals
            .as_ref()
            .and_then(|n| {
                let [na, nb, nc] = n[prim as usize].map(widen);
                normalize(std::array::from_fn(|i| w * na[i] + u * nb[i] + v * nc[i]))
            })
            .filter(|n| dot(*n, wound_normal) > 0.0)
            .unwrap_or(wound_normal);
        let surface = self.surfaces[self.surface_of[prim as usize] as usize];
        Some(SurfacePoint { point, wound_normal, shading_normal, surface })
    }
}

/// Per-corner normals: the area-weighted average of the normals of the triangles that share the
/// corner's vertex (the same f32 position) and face within `crease_degrees` of the corner's own
/// triangle. Deterministic: vertices are grouped by sorting.
fn smooth_normals(triangles: &[[[f32; 3]; 3]], crease_degrees: f64) -> Vec<[[f32; 3]; 3]> {
    let cos_crease = crease_degrees.to_radians().cos();
    // Area-weighted and unit face normals.
    let faces: Vec<(V3, V3)> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(widen);
            let n = cross(std::array::from_fn(|i| b[i] - a[i]), std::array::from_fn(|i| c[i] - a[i]));
            (n, normalize(n).unwrap_or([0.0; 3]))
        })
        .collect();
    let mut normals: Vec<[[f32; 3]; 3]> = faces.iter().map(|(_, u)| [u.map(|c| c as f32); 3]).collect();
    let mut corners: Vec<([u32; 3], u32, u8)> = Vec::with_capacity(triangles.len() * 3);
    for (i, t) in triangles.iter().enumerate() {
        for (k, v) in t.iter().enumerate() {
            corners.push((v.map(|c| (c + 0.0).to_bits()), i as u32, k as u8));
        }
    }
    corners.sort_unstable();
    for group in corners.chunk_by(|a, b| a.0 == b.0) {
        if group.len() < 2 || group.len() > MAX_SMOOTHING_VALENCE {
            continue;
        }
        for &(_, tri, corner) in group {
            let own = faces[tri as usize].1;
            let mut sum = [0.0; 3];
            for &(_, other, _) in group {
                let (weighted, unit) = faces[other as usize];
                if dot(unit, own) >= cos_crease {
                    sum = std::array::from_fn(|i| sum[i] + weighted[i]);
                }
            }
            if let Some(n) = normalize(sum) {
                normals[tri as usize][corner as usize] = n.map(|c| c as f32);
            }
        }
    }
    normals
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles folded along a shared edge: averaged across a gentle fold, kept apart across a
    /// sharp one (the crease angle).
    #[test]
    fn normals_are_smoothed_across_gentle_folds_only() {
        let fold = |height: f32| {
            vec![
                [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                [[1.0, 0.0, 0.0], [1.0, 1.0, height], [0.0, 1.0, 0.0]],
            ]
        };
        let gentle = smooth_normals(&fold(0.3), 40.0);
        let edge = gentle[0][1];
        assert_eq!(edge, gentle[1][0], "both triangles share the edge's normal");
        assert!(edge[2] > 0.9 && edge[0] < 0.0, "between the two faces: {edge:?}");
        assert_eq!(gentle[0][0], [0.0, 0.0, 1.0], "a vertex of one face only keeps its normal");
        let sharp = smooth_normals(&fold(3.0), 40.0);
        assert_eq!(sharp[0][1], [0.0, 0.0, 1.0]);
        assert_ne!(sharp[1][0], sharp[0][1]);
    }

    #[test]
    fn damaged_materials_become_finite_non_negative_surfaces() {
        let m = Material {
            name: "",
            input: 0,
            index: 0,
            diffuse: [f32::NAN, -1.0, 0.5],
            shininess: f32::INFINITY,
            specular: [0.0; 3],
            ior: -2.0,
            reflection: [f32::INFINITY; 3],
            transmission: [0.0; 3],
            emission: [0.0; 3],
        };
        let s = Surface::from_material(&m);
        assert_eq!((s.diffuse, s.shininess, s.ior, s.reflection), ([0.0, 0.0, 0.5], 1.0, 1.0, [0.0; 3]));
    }
}
