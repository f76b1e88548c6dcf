//! Scene preparation: the scene's bounding sphere around its centre, and its triangles as indices
//! into unique vertices (relative to the centre, as stored), computed once for all directions.

use crate::scene::Scene;

/// The scene prepared once for all directions: unique vertices relative to the scene's centre and
/// triangles as vertex indices.
pub struct Prepared<'a> {
    pub scene: &'a Scene,
    /// The scene's centre, world units (`Scene::center`): the sphere's centre and the origin of
    /// every coordinate below.
    pub center: [f64; 3],
    /// The radius of the sphere around the centre that holds every vertex.
    pub radius: f64,
    /// The box around every vertex, relative to the centre.
    pub aabb: ([f64; 3], [f64; 3]),
    /// Unique vertex positions as stored (relative to the centre), in f64.
    pub(crate) vertices: Vec<[f64; 3]>,
    /// Each triangle's three indices into `vertices`, in triangle-id order.
    pub(crate) triangles: Vec<[u32; 3]>,
}

impl<'a> Prepared<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let mut index = std::collections::HashMap::with_capacity(scene.triangles.len());
        let mut unique: Vec<[f32; 3]> = Vec::with_capacity(scene.triangles.len());
        let mut triangles = Vec::with_capacity(scene.triangles.len());
        for t in &scene.triangles {
            let mut tri = [0u32; 3];
            for (k, slot) in tri.iter_mut().enumerate() {
                let v = t.vertex(k);
                // Bit patterns as keys: -0.0 and 0.0 stay distinct, which is harmless.
                let key = v.map(f32::to_bits);
                *slot = *index.entry(key).or_insert_with(|| {
                    unique.push(v);
                    (unique.len() - 1) as u32
                });
            }
            triangles.push(tri);
        }
        let vertices: Vec<[f64; 3]> = unique.iter().map(|v| v.map(f64::from)).collect();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &vertices {
            for i in 0..3 {
                lo[i] = lo[i].min(v[i]);
                hi[i] = hi[i].max(v[i]);
            }
        }
        let r2 = vertices.iter().map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).fold(0.0f64, f64::max);
        // Grown a little so every vertex is strictly inside despite rounding.
        let radius = r2.sqrt() * (1.0 + 1e-9) + f64::MIN_POSITIVE;
        Prepared { scene, center: scene.center, radius, aabb: (lo, hi), vertices, triangles }
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}
