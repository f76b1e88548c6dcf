//! The ray sets of the peers benchmark, one array each, traced by every contestant.
//!
//! - `outside`, `inside`: primary rays of a `resolution²` image from the cameras of
//!   `vlf-bake rays --view outside|inside` (`vlf_geom::Camera::outside` / `inside` on the field's
//!   bounding sphere, aspect 1).
//! - `incoherent`: origins uniform in the scene's bounding box, directions uniform on the sphere
//!   (seeded), unbounded.
//! - `shadow-outside`, `shadow-inside`: any-hit rays from each hit of the primary rays towards a
//!   point light at `centre + (0.3, 3, 0.2)·R` (above the scene; `R` the bounding sphere's
//!   radius): origin the hit point, direction the light minus the origin (so the light is at
//!   `t = 1`), `t` on `[10⁻⁴, 1 − 10⁻⁴]`: the ray leaves the surface and stops just short of the light.

use super::model::{Query, Tri};
use super::scenes::bounds;
use vlf_bake::generate::Rng;
use vlf_geom::{Camera, Ray};

/// One named array of rays and the query it asks.
#[derive(Clone, Debug)]
pub struct RaySet {
    pub name: &'static str,
    pub query: Query,
    pub rays: Vec<Ray>,
}

/// Where the point light of the shadow rays sits, relative to the bounding sphere.
pub const LIGHT_OFFSET: [f64; 3] = [0.3, 3.0, 0.2];
/// The shadow rays' interval in units of the segment from the hit to the light.
pub const SHADOW_T: (f32, f32) = (1e-4, 1.0 - 1e-4);

/// The two primary sets.
pub fn primary(center: [f64; 3], radius: f64, resolution: u32) -> [RaySet; 2] {
    [
        RaySet {
            name: "outside",
            query: Query::Closest,
            rays: Camera::outside(center, radius, 1.0).primary_rays(resolution, resolution),
        },
        RaySet {
            name: "inside",
            query: Query::Closest,
            rays: Camera::inside(center, radius, 1.0).primary_rays(resolution, resolution),
        },
    ]
}

/// `count` rays with origins uniform in the triangles' bounding box and directions uniform on
/// the unit sphere, from `seed`.
pub fn incoherent(tris: &[Tri], count: usize, seed: u64) -> RaySet {
    let (lo, hi) = bounds(tris);
    let mut rng = Rng::new(seed);
    let rays = (0..count)
        .map(|_| {
            let org: [f32; 3] = std::array::from_fn(|k| rng.range(lo[k], hi[k]) as f32);
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, std::f64::consts::TAU);
            let s = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(org, [(s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32])
        })
        .collect();
    RaySet { name: "incoherent", query: Query::Closest, rays }
}

/// The light of the shadow rays.
pub fn light(center: [f64; 3], radius: f64) -> [f64; 3] {
    std::array::from_fn(|k| center[k] + LIGHT_OFFSET[k] * radius)
}

/// Shadow rays from the hits of `primary` (given as the `t` of each ray's closest hit, `None` for
/// a miss) towards `light`.
pub fn shadow(name: &'static str, primary: &[Ray], hits: &[Option<f32>], light: [f64; 3]) -> RaySet {
    let rays = primary
        .iter()
        .zip(hits)
        .filter_map(|(r, h)| {
            let p = r.at((*h)? as f64);
            let org = p.map(|c| c as f32);
            let dir: [f32; 3] = std::array::from_fn(|k| (light[k] - org[k] as f64) as f32);
            Some(Ray::with_interval(org, dir, SHADOW_T.0, SHADOW_T.1))
        })
        .collect();
    RaySet { name, query: Query::Any, rays }
}

/// A seeded sample of `k` distinct indices below `n` (all of them, in order, when `k >= n`), sorted.
pub fn sample(n: usize, k: usize, seed: u64) -> Vec<usize> {
    if k >= n {
        return (0..n).collect();
    }
    let mut idx: Vec<usize> = (0..n).collect();
    let mut rng = Rng::new(seed);
    for i in 0..k {
        let j = i + (rng.next_u64() % (n - i) as u64) as usize;
        idx.swap(i, j);
    }
    idx.truncate(k);
    idx.sort_unstable();
    idx
}
