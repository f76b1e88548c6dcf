//! obvhs (a Rust CWBVH: PLOC build, reinsertion, compressed 8-wide nodes, SIMD traversal) as a
//! contestant: `build_cwbvh_from_tris` at its `medium_build` preset ("around the same build time
//! as Embree"), its triangles reordered into leaf order as `RtTriangle`s, and its own triangle
//! test (`RtTriangle::intersect`, Möller–Trumbore in f32). Built with obvhs's `parallel` feature.

use super::contestant::{Contestant, PeerHit};
use super::model::Tri;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::RayHit;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use std::time::{Duration, Instant};
use vlf_geom::Ray;

pub struct ObvhsContestant {
    bvh: CwBvh,
    /// `bvh.primitive_indices[i]`'s triangle, in leaf order.
    triangles: Vec<RtTriangle>,
    build_seconds: f64,
}

fn v3(p: [f32; 3]) -> Vec3A {
    Vec3A::from_array(p)
}

fn to_obvhs(ray: &Ray) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new(v3(ray.org), v3(ray.dir), ray.tmin, ray.tmax)
}

impl ObvhsContestant {
    /// Builds the CWBVH; the build time covers converting the triangles, the build and the
    /// reordering of the triangles into leaf order.
    pub fn build(tris: &[Tri]) -> ObvhsContestant {
        let start = Instant::now();
        let input: Vec<Triangle> = tris.iter().map(|t| Triangle { v0: v3(t[0]), v1: v3(t[1]), v2: v3(t[2]) }).collect();
        let bvh = build_cwbvh_from_tris(&input, BvhBuildParams::medium_build(), &mut Duration::default());
        let triangles = bvh.primitive_indices.iter().map(|&i| RtTriangle::from(&input[i as usize])).collect();
        ObvhsContestant { bvh, triangles, build_seconds: start.elapsed().as_secs_f64() }
    }
}

impl Contestant for ObvhsContestant {
    fn name(&self) -> &'static str {
        "obvhs"
    }
    fn describe(&self) -> String {
        format!("CWBVH medium_build, {} nodes", self.bvh.nodes.len())
    }
    fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
    fn bytes(&self) -> u64 {
        (self.bvh.nodes.len() * size_of::<CwBvhNode>()
            + self.bvh.primitive_indices.len() * size_of::<u32>()
            + self.triangles.len() * size_of::<RtTriangle>()) as u64
    }
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit> {
        let mut hit = RayHit::none();
        let tris = &self.triangles;
        if self.bvh.ray_traverse(to_obvhs(ray), &mut hit, |r, id| tris[id].intersect(r)) {
            Some(PeerHit { t: hit.t, prim: self.bvh.primitive_indices[hit.primitive_id as usize] })
        } else {
            None
        }
    }
    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        let tris = &self.triangles;
        !self.bvh.ray_traverse_miss(to_obvhs(ray), |r, id| tris[id].intersect(r))
    }
}
