//! Rays and hits, laid out exactly as the batch files of `formats/rays.md`.

use bytemuck::{Pod, Zeroable};

/// A ray: `org + t·dir` for `t` in `[tmin, tmax]`. `dir` need not be unit length; `t` is measured
/// in units of `dir` (as in Embree). 32 bytes, the record of a rays file.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Origin.
    pub org: [f32; 3],
    /// Start of the interval; usually 0.
    pub tmin: f32,
    /// Direction; any nonzero length.
    pub dir: [f32; 3],
    /// End of the interval; `f32::INFINITY` for an unbounded ray.
    pub tmax: f32,
}

impl Ray {
    /// The ray from `org` along `dir` on `[0, +∞]`.
    pub fn new(org: [f32; 3], dir: [f32; 3]) -> Self {
        Ray { org, tmin: 0.0, dir, tmax: f32::INFINITY }
    }

    /// The ray from `org` along `dir` on `[tmin, tmax]` (a segment, or a shadow ray that stops
    /// short of its light).
    pub fn with_interval(org: [f32; 3], dir: [f32; 3], tmin: f32, tmax: f32) -> Self {
        Ray { org, tmin, dir, tmax }
    }

    /// The rays of a rays file's bytes (`formats/rays.md`: 32-byte little-endian records, this
    /// struct's layout), or `None` if the bytes are not a whole number of records. Rays are not
    /// checked: an invalid one misses.
    pub fn from_records(bytes: &[u8]) -> Option<Vec<Ray>> {
        bytes.len().is_multiple_of(size_of::<Ray>()).then(|| bytemuck::pod_collect_to_vec(bytes))
    }

    /// Whether the ray can be traced: finite origin and direction, a nonzero direction, and an
    /// interval `tmin ≤ tmax` without NaN. Invalid rays miss.
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.org.iter().all(|c| c.is_finite())
            && self.dir.iter().all(|c| c.is_finite())
            && self.dir.iter().any(|&c| c != 0.0)
            && self.tmin <= self.tmax
    }

    /// The point at parameter `t`, in f64.
    pub fn at(&self, t: f64) -> [f64; 3] {
        std::array::from_fn(|i| self.org[i] as f64 + t * self.dir[i] as f64)
    }
}

/// A hit: parameter `t`, triangle id `prim`, and barycentric weights `u` of `v1` and `v` of `v2`.
/// 16 bytes, the record of a hits file.
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
#[repr(C)]
pub struct Hit {
    /// The ray parameter: the hit point is `org + t·dir` (`+inf` in [`Hit::MISS`]).
    pub t: f32,
    /// The triangle id: an index into the field's triangles (`u32::MAX` in [`Hit::MISS`]).
    pub prim: u32,
    /// Barycentric weight of the triangle's `v1`.
    pub u: f32,
    /// Barycentric weight of the triangle's `v2`: the hit point is `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub v: f32,
}

impl Hit {
    /// The record written for a miss.
    pub const MISS: Hit = Hit { t: f32::INFINITY, prim: u32::MAX, u: 0.0, v: 0.0 };

    /// The hits-file record of an optional hit.
    pub fn record(hit: Option<Hit>) -> Hit {
        hit.unwrap_or(Hit::MISS)
    }
}

/// Something that answers ray queries: the field, the kd-tree baseline and the brute-force
/// reference all implement it, so tests, benchmarks and the renderer treat them alike.
///
/// Rays are f32 ([`Ray`]), so a world-space ray origin far from the world's origin is coarse (at
/// 10⁹ f32 numbers are 64 apart). A tracer whose triangles are stored relative to a point (a
/// field's centre) therefore also answers *local* rays, whose origin is given relative to
/// [`Intersector::origin`]: a caller that computes `point − origin` in f64 before rounding keeps
/// the precision of the scene's own size however far the scene is (the renderer does).
pub trait Intersector: Sync {
    /// The closest hit in `[tmin, tmax]`, if any.
    fn closest_hit(&self, ray: &Ray) -> Option<Hit>;
    /// Whether anything is hit in `[tmin, tmax]` (shadow rays).
    fn any_hit(&self, ray: &Ray) -> bool;
    /// [`Self::closest_hit`], adding the work done to `work`.
    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit>;
    /// The first hit found in `[tmin, tmax]` (not necessarily the closest), adding the work done
    /// to `work`: [`Self::any_hit`] with the hit it found.
    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit>;

    /// The point, in world coordinates, that the origins of local rays are relative to
    /// ([`Self::closest_hit_local_counted`]): the world's origin unless the tracer says otherwise.
    fn origin(&self) -> [f64; 3] {
        [0.0; 3]
    }

    /// [`Self::closest_hit_counted`] for a ray whose origin is given relative to
    /// [`Self::origin`]; `t`, `u`, `v` and `prim` mean what they mean for world rays. The default
    /// traces it as a world ray, which is right only while [`Self::origin`] is zero: a tracer that
    /// overrides one overrides all three.
    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.closest_hit_counted(ray, work)
    }

    /// [`Self::any_hit_counted`] for a ray given relative to [`Self::origin`], as
    /// [`Self::closest_hit_local_counted`].
    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.any_hit_counted(ray, work)
    }
}

/// Counters of the work traversals did, shared by every acceleration structure so benchmarks
/// compare like with like: rays that reached the structure, cells visited (tiles for the field,
/// nodes for the kd-tree), leaves visited and ray/triangle tests (a triangle referenced by several
/// visited leaves counts each time).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Rays that reached the structure (invalid rays and rays that miss the scene's bounds do not).
    pub rays: u64,
    /// Cells visited: tiles for the field, nodes for the kd-tree.
    pub cells: u64,
    /// Leaves visited.
    pub leaves: u64,
    /// Ray/triangle tests.
    pub triangle_tests: u64,
}

impl TraceStats {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &TraceStats) {
        self.rays += other.rays;
        self.cells += other.cells;
        self.leaves += other.leaves;
        self.triangle_tests += other.triangle_tests;
    }
}

/// What a traversal counts. `()` counts nothing and compiles away.
pub trait Counter {
    /// A ray reached the structure.
    fn ray(&mut self) {}
    /// A cell (tile or node) was visited.
    fn cell(&mut self) {}
    /// A leaf was visited.
    fn leaf(&mut self) {}
    /// A ray/triangle test was run.
    fn test(&mut self) {}
}

impl Counter for () {}

impl Counter for TraceStats {
    #[inline(always)]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline(always)]
    fn cell(&mut self) {
        self.cells += 1;
    }
    #[inline(always)]
    fn leaf(&mut self) {
        self.leaves += 1;
    }
    #[inline(always)]
    fn test(&mut self) {
        self.triangle_tests += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_read_back_from_their_records_and_partial_records_are_refused() {
        let rays =
            [Ray::new([1.0, 2.0, 3.0], [0.0, 0.0, 1.0]), Ray::with_interval([0.5; 3], [1.0, 0.0, 0.0], 0.25, 4.0)];
        let bytes: &[u8] = bytemuck::cast_slice(&rays);
        assert_eq!(bytes.len(), 64);
        assert_eq!(Ray::from_records(bytes), Some(rays.to_vec()));
        assert_eq!(Ray::from_records(&[]), Some(vec![]));
        assert_eq!(Ray::from_records(&bytes[..33]), None);
        assert_eq!(Ray::from_records(&bytes[..31]), None);
    }
}
