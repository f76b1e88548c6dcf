//! Embree 3's two-level instancing through the C shim `embree_instances.c`: one BVH over the
//! mesh, an instance geometry per placement, and a top-level BVH rebuilt by `rtcCommitScene`
//! (flags `RTC_SCENE_FLAG_DYNAMIC`, `RTC_BUILD_QUALITY_LOW`, what Embree recommends for a top
//! level rebuilt every frame).

use std::ffi::{c_int, c_uint};
use vlf_geom::Ray;

#[repr(C)]
struct Handle {
    _private: [u8; 0],
}

unsafe extern "C" {
    fn vlf_embree_inst_new(triangles: *const f32, count: usize, instances: c_uint) -> *mut Handle;
    fn vlf_embree_inst_set(e: *mut Handle, i: c_uint, rows: *const f32);
    fn vlf_embree_inst_commit(e: *mut Handle) -> c_int;
    fn vlf_embree_inst_intersect1(
        e: *const Handle,
        ray: *const Ray,
        t: *mut f32,
        inst: *mut c_uint,
        prim: *mut c_uint,
    ) -> c_int;
    fn vlf_embree_inst_occluded1(e: *const Handle, ray: *const Ray) -> c_int;
    fn vlf_embree_inst_free(e: *mut Handle);
}

/// A mesh placed `count` times by Embree.
pub struct EmbreeInstances {
    handle: *mut Handle,
    count: u32,
}

// SAFETY: between commits the scene is immutable and Embree's query functions may be called from
// any number of threads at once (Embree API documentation, "Thread safety"); the methods that
// change it take `&mut self`, so no query runs meanwhile; the handle is freed only in `drop`.
unsafe impl Send for EmbreeInstances {}
unsafe impl Sync for EmbreeInstances {}

impl EmbreeInstances {
    /// The mesh's BVH and `count` instances of it with identity transforms (not committed).
    pub fn new(tris: &[[[f32; 3]; 3]], count: u32) -> anyhow::Result<EmbreeInstances> {
        // SAFETY: `tris` is `len` triangles of 9 contiguous f32, which the shim copies before
        // returning; the result is checked for null.
        let handle = unsafe { vlf_embree_inst_new(tris.as_ptr().cast(), tris.len(), count) };
        anyhow::ensure!(!handle.is_null(), "Embree refused the device or the mesh");
        Ok(EmbreeInstances { handle, count })
    }

    /// Sets instance `i`'s transform (`rows` of `[A | b]`, f64 rounded to f32). Call
    /// [`EmbreeInstances::commit`] before querying.
    pub fn set(&mut self, i: u32, rows: [[f64; 4]; 3]) {
        assert!(i < self.count, "instance {i} of {}", self.count);
        let flat: [f32; 12] = std::array::from_fn(|k| rows[k / 4][k % 4] as f32);
        // SAFETY: a live handle, `i` in range (checked), 12 floats.
        unsafe { vlf_embree_inst_set(self.handle, i, flat.as_ptr()) }
    }

    /// Rebuilds the top level.
    pub fn commit(&mut self) -> anyhow::Result<()> {
        // SAFETY: a live handle, not queried meanwhile (`&mut self`).
        let err = unsafe { vlf_embree_inst_commit(self.handle) };
        anyhow::ensure!(err == 0, "rtcCommitScene failed with RTCError {err}");
        Ok(())
    }

    /// The closest hit: `(t, instance, triangle)`.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<(f32, u32, u32)> {
        let (mut t, mut inst, mut prim) = (0f32, 0u32, 0u32);
        // SAFETY: a committed scene (see the Sync impl); `ray` mirrors the shim's struct; the
        // outputs are live locals.
        let hit = unsafe { vlf_embree_inst_intersect1(self.handle, ray, &mut t, &mut inst, &mut prim) };
        (hit != 0).then_some((t, inst, prim))
    }

    /// Whether anything is hit.
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        // SAFETY: as in `closest_hit`.
        unsafe { vlf_embree_inst_occluded1(self.handle, ray) != 0 }
    }
}

impl Drop for EmbreeInstances {
    fn drop(&mut self) {
        // SAFETY: the handle came from vlf_embree_inst_new and is freed once, here.
        unsafe { vlf_embree_inst_free(self.handle) }
    }
}
