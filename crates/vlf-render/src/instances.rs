//! The shading scene of a dynamic scene (`vlf_scene::Scene`): every instance's triangles in
//! world coordinates, numbered as [`vlf_scene::Flat`] numbers them, with the surfaces of their
//! fields' materials, so that [`crate::render`] can shade what a `Flat` hits.
//!
//! Building it costs time proportional to the triangles of every instance (the shading data,
//! normals included, are in world space); the acceleration structure itself is the scene's, and
//! moving an instance costs it nothing of the sort. A renderer of many frames builds this once
//! per frame.

use crate::scene::{Scene, SceneOptions, Surface};
use vlf_scene::{Flat, Scene as Instances};

impl Scene {
    /// The shading scene of `instances` as `flat` numbers its triangles: triangle `k` is the
    /// world triangle `flat.resolve(k)` names (a removed one is left degenerate: it is never hit),
    /// with its field's material, or the default surface for inserted triangles.
    pub fn from_instances(instances: &Instances, flat: &Flat<'_>, options: &SceneOptions) -> Scene {
        // The centre is the one `Flat` traces relative to, so hit points need no shift.
        let (lo, hi) = instances.content_bounds();
        let (center, radius) = if (0..3).all(|k| lo[k] <= hi[k]) {
            let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
            (c, (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt() / 2.0)
        } else {
            ([0.0; 3], 1.0)
        };
        // Each field's materials, one after the other.
        let mut surfaces = Vec::new();
        let mut first_surface = Vec::with_capacity(instances.fields().len());
        for f in instances.fields() {
            first_surface.push(surfaces.len() as u32);
            surfaces.extend(f.field().materials().map(|m| Surface::from_material(&m)));
        }
        // Past every field's materials: the default surface (`Scene::new` adds it there).
        let default = surfaces.len() as u32;
        let count = flat.count() as usize;
        let mut triangles = vec![[[0.0f32; 3]; 3]; count];
        let mut surface_of = vec![default; count];
        for id in instances.instance_ids() {
            let Some(info) = instances.instance(id) else { continue };
            let Some(f) = instances.field(info.field) else { continue };
            let base = f.field().triangle_count();
            for prim in 0..f.id_count() {
                let (Some(k), Some(t)) = (flat.number(id, prim), instances.world_triangle(id, prim)) else { continue };
                let Some(slot) = triangles.get_mut(k as usize) else { continue };
                *slot = t.map(|v| std::array::from_fn(|i| (v[i] - center[i]) as f32));
                if prim < base
                    && let Some(m) = f.field().material_index(prim)
                {
                    surface_of[k as usize] = first_surface[info.field.0 as usize] + m as u32;
                }
            }
        }
        Scene::new(triangles, center, surfaces, surface_of, center, radius, options)
    }
}
