//! What the renderer asks of an acceleration structure: closest-hit and any-hit queries that count
//! their work. The field, the kd-tree baseline and the brute-force reference implement it; they
//! share the watertight kernel, so the same rays give the same hits, and the same pictures.

use vlf_geom::{BruteForce, Hit, Ray, TraceStats, TriRay};
use vlf_kdtree::KdTree;
use vlf_runtime::{Field, FieldView};

/// A ray tracer's queries, counting into `work` (rays, cells, leaves, triangle tests).
pub trait Tracer: Sync {
    /// The closest hit on the ray's interval.
    fn closest_hit(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit>;
    /// Whether anything is hit on the ray's interval (shadow rays).
    fn any_hit(&self, ray: &Ray, work: &mut TraceStats) -> bool;
}

impl Tracer for FieldView<'_> {
    #[inline]
    fn closest_hit(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.closest_hit_counted(ray, work)
    }
    #[inline]
    fn any_hit(&self, ray: &Ray, work: &mut TraceStats) -> bool {
        self.any_hit_counted(ray, work).is_some()
    }
}

impl Tracer for Field {
    #[inline]
    fn closest_hit(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.view().closest_hit_counted(ray, work)
    }
    #[inline]
    fn any_hit(&self, ray: &Ray, work: &mut TraceStats) -> bool {
        self.view().any_hit_counted(ray, work).is_some()
    }
}

impl Tracer for KdTree {
    #[inline]
    fn closest_hit(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.closest_hit_counted(ray, work)
    }
    #[inline]
    fn any_hit(&self, ray: &Ray, work: &mut TraceStats) -> bool {
        self.any_hit_counted(ray, work).is_some()
    }
}

/// Every triangle for every ray; counts one ray and one test per triangle.
impl Tracer for BruteForce<'_> {
    fn closest_hit(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        work.rays += 1;
        work.triangle_tests += self.triangles.len() as u64;
        let tr = TriRay::new(ray);
        let mut best = None;
        let mut tmax = ray.tmax;
        for (i, t) in self.triangles.iter().enumerate() {
            if let Some(h) = tr.intersect(t[0], t[1], t[2], tmax) {
                tmax = h.t;
                best = Some(Hit { t: h.t, prim: i as u32, u: h.u, v: h.v });
            }
        }
        best
    }
    fn any_hit(&self, ray: &Ray, work: &mut TraceStats) -> bool {
        if !ray.is_valid() {
            return false;
        }
        work.rays += 1;
        let tr = TriRay::new(ray);
        for t in self.triangles {
            work.triangle_tests += 1;
            if tr.intersect(t[0], t[1], t[2], ray.tmax).is_some() {
                return true;
            }
        }
        false
    }
}
