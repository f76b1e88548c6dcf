//! Embree 3 (Debian's `libembree-dev`, 3.13) as a contestant, through the C shim
//! `embree_shim.c`: default device, default scene flags and build quality, one triangle geometry
//! (an unindexed soup, as the field stores it), `rtcIntersect1` / `rtcOccluded1` one ray per call.
//! Memory comes from `rtcSetDeviceMemoryMonitorFunction`: everything the device holds after the
//! build (vertex and index buffers and the BVH).

use super::contestant::{Contestant, PeerHit};
use super::model::Tri;
use std::ffi::{c_char, c_int, c_uint};
use std::time::Instant;
use vlf_geom::Ray;

#[repr(C)]
struct Handle {
    _private: [u8; 0],
}

unsafe extern "C" {
    fn vlf_embree_new(config: *const c_char) -> *mut Handle;
    fn vlf_embree_build(e: *mut Handle, triangles: *const f32, count: usize, before_commit: *mut i64) -> c_int;
    fn vlf_embree_bytes(e: *const Handle) -> i64;
    fn vlf_embree_peak(e: *const Handle) -> i64;
    fn vlf_embree_intersect1(
        e: *const Handle,
        ray: *const Ray,
        t: *mut f32,
        prim: *mut c_uint,
        u: *mut f32,
        v: *mut f32,
    ) -> c_int;
    fn vlf_embree_occluded1(e: *const Handle, ray: *const Ray) -> c_int;
    fn vlf_embree_free(e: *mut Handle);
}

/// An Embree device holding one committed scene.
pub struct EmbreeContestant {
    handle: *mut Handle,
    build_seconds: f64,
    bytes: u64,
    bvh_bytes: u64,
    peak_bytes: u64,
}

// SAFETY: after `rtcCommitScene` returns, Embree's scene is immutable and its query functions
// (rtcIntersect1, rtcOccluded1) may be called from any number of threads at once (Embree API
// documentation, "Thread safety"); the handle is never mutated after `build` and is freed only in
// `drop`, which has exclusive access.
unsafe impl Send for EmbreeContestant {}
unsafe impl Sync for EmbreeContestant {}

impl EmbreeContestant {
    /// [`Self::build`] over a field's own triangles, in world coordinates rounded to f32 (its stored
    /// vertices plus its origin), so that triangle ids agree with the field's: what the examples
    /// that time the two on ray files build.
    pub fn over_field(field: &vlf_runtime::Field) -> anyhow::Result<EmbreeContestant> {
        let tris: Vec<Tri> = (0..field.triangle_count())
            .map(|i| field.triangle(i).expect("below the count").map(|v| v.map(|c| c as f32)))
            .collect();
        Self::build(&tris)
    }

    /// A default device (`rtcNewDevice(NULL)`: all hardware threads build) and the scene of `tris`.
    /// The build time covers filling the buffers and `rtcCommitScene`, not creating the device.
    pub fn build(tris: &[Tri]) -> anyhow::Result<EmbreeContestant> {
        // SAFETY: a null config asks for the defaults; the result is checked for null.
        let handle = unsafe { vlf_embree_new(std::ptr::null()) };
        anyhow::ensure!(!handle.is_null(), "rtcNewDevice failed");
        let mut me = EmbreeContestant { handle, build_seconds: 0.0, bytes: 0, bvh_bytes: 0, peak_bytes: 0 };
        let mut before_commit = 0i64;
        let start = Instant::now();
        // SAFETY: `tris` is `count` triangles of 9 contiguous f32 (`[[f32; 3]; 3]` has no padding),
        // which the shim copies into Embree's own buffers before returning.
        let err = unsafe { vlf_embree_build(handle, tris.as_ptr().cast(), tris.len(), &mut before_commit) };
        me.build_seconds = start.elapsed().as_secs_f64();
        anyhow::ensure!(err == 0, "Embree's build failed with RTCError {err}");
        // SAFETY: the handle is live; the counters are read atomically by the shim.
        let (bytes, peak) = unsafe { (vlf_embree_bytes(handle), vlf_embree_peak(handle)) };
        me.bytes = bytes.max(0) as u64;
        me.peak_bytes = peak.max(0) as u64;
        me.bvh_bytes = (bytes - before_commit).max(0) as u64;
        Ok(me)
    }

    /// Of [`Contestant::bytes`], what the BVH takes (the rest is the vertex and index buffers).
    pub fn bvh_bytes(&self) -> u64 {
        self.bvh_bytes
    }

    /// The most the device held at any time during the build.
    pub fn peak_bytes(&self) -> u64 {
        self.peak_bytes
    }
}

impl Drop for EmbreeContestant {
    fn drop(&mut self) {
        // SAFETY: the handle came from vlf_embree_new and is freed once, here.
        unsafe { vlf_embree_free(self.handle) }
    }
}

impl Contestant for EmbreeContestant {
    fn name(&self) -> &'static str {
        "embree"
    }
    fn describe(&self) -> String {
        format!(
            "Embree 3 defaults; BVH {:.1} MiB, build peak {:.1} MiB",
            self.bvh_bytes as f64 / (1u64 << 20) as f64,
            self.peak_bytes as f64 / (1u64 << 20) as f64
        )
    }
    fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
    fn bytes(&self) -> u64 {
        self.bytes
    }
    #[inline]
    fn closest_hit(&self, ray: &Ray) -> Option<PeerHit> {
        let (mut t, mut prim, mut u, mut v) = (0f32, 0u32, 0f32, 0f32);
        // SAFETY: the scene is committed (see the Sync impl); `ray` is a live vlf_geom::Ray, whose
        // layout the shim's vlf_ray mirrors; the outputs are live locals.
        let hit = unsafe { vlf_embree_intersect1(self.handle, ray, &mut t, &mut prim, &mut u, &mut v) };
        (hit != 0).then_some(PeerHit { t, prim })
    }
    #[inline]
    fn any_hit(&self, ray: &Ray) -> bool {
        // SAFETY: as in `closest_hit`.
        unsafe { vlf_embree_occluded1(self.handle, ray) != 0 }
    }
}
