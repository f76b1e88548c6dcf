//! Dynamic scenes from C (`vlf_scene::Scene`): fields mapped once and placed by affine
//! transforms as instances with masks, moved every frame, and edited the paper's way (triangles
//! removed, meshes inserted) in memory.
//!
//! Thread safety: the query functions (`vlf_scene_closest_hit`, `vlf_scene_any_hit`,
//! `vlf_scene_closest_hits`) may run on the same scene from any number of threads at once; every
//! other function changes the scene and must not run concurrently with any other use of it.

use crate::boundary::{self, *};
use crate::types::VlfStatus::*;
use crate::types::*;
use std::ffi::{CStr, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use vlf_runtime::{Hit, OpenOptions};
use vlf_scene::{Affine, EditError, EditedField, FieldId, Object, Scene, SceneError};

/// A scene of instances. Opaque: create it with `vlf_scene_create`, release it with
/// `vlf_scene_destroy`.
pub struct VlfScene {
    scene: Scene,
}

/// The instance id of a miss (`0xFFFFFFFF`), in `vlf_scene_closest_hit`'s `instance`.
pub const VLF_NO_INSTANCE: u32 = u32::MAX;

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Failure {
        let status = if matches!(e, SceneError::TooManyInstances) { VLF_ERR_LIMIT } else { VLF_ERR_INVALID_ARGUMENT };
        Failure { status, message: e.to_string() }
    }
}

impl From<EditError> for Failure {
    fn from(e: EditError) -> Failure {
        let status = match e {
            EditError::TooManyTriangles | EditError::TooLarge => VLF_ERR_LIMIT,
            _ => VLF_ERR_INVALID_ARGUMENT,
        };
        Failure { status, message: e.to_string() }
    }
}

/// The scene behind a handle.
///
/// # Safety
/// A non-null `scene` must come from `vlf_scene_create` and not have been destroyed.
unsafe fn scene_arg<'a>(scene: *const VlfScene) -> Result<&'a Scene, Failure> {
    // SAFETY: the caller's promise.
    Ok(&unsafe { arg(scene, "scene") }?.scene)
}

/// The scene behind a handle, to change.
///
/// # Safety
/// A non-null `scene` must come from `vlf_scene_create`, not have been destroyed, and not be in
/// use by another call meanwhile.
unsafe fn scene_mut<'a>(scene: *mut VlfScene) -> Result<&'a mut Scene, Failure> {
    if scene.is_null() {
        return Err(Failure::null("scene"));
    }
    if !scene.is_aligned() {
        return Err(Failure::invalid(format!("argument `scene` is not aligned to {} bytes", align_of::<VlfScene>())));
    }
    // SAFETY: non-null and aligned; a live, unshared handle by the caller's promise.
    Ok(&mut unsafe { &mut *scene }.scene)
}

/// The transform at `m` (16 doubles, a row-major 4×4 affine matrix), or the identity for NULL.
///
/// # Safety
/// `m` must be NULL or point to 16 doubles.
unsafe fn transform_arg(m: *const f64, argument: &str) -> Result<Affine, Failure> {
    if m.is_null() {
        return Ok(Affine::IDENTITY);
    }
    // SAFETY: the caller's promise.
    let m = unsafe { slice_arg(m, 16, argument) }?;
    let m: &[f64; 16] =
        m.try_into().map_err(|_| Failure::invalid(format!("argument `{argument}` is not 16 numbers")))?;
    Affine::from_rows(m).map_err(|e| Failure::invalid(format!("argument `{argument}` is not usable: {e}")))
}

/// A field id the scene has.
fn field_id(scene: &Scene, field: u32) -> Result<FieldId, Failure> {
    scene
        .field(FieldId(field))
        .map(|_| FieldId(field))
        .ok_or_else(|| SceneError::NoSuchField(field, scene.fields().len()).into())
}

/// Creates an empty scene in `*out`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT` or `VLF_ERR_INVALID_ARGUMENT` (a misaligned `out`).
///
/// # Safety
/// `out` must be NULL or valid for writing a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_create(out: *mut *mut VlfScene) -> VlfStatus {
    call("vlf_scene_create", || {
        // SAFETY: the caller's promise.
        let slot = unsafe { boundary::out(out, "out") }?;
        slot.write(Box::into_raw(Box::new(VlfScene { scene: Scene::new() })));
        Ok(())
    })
}

/// Destroys a scene: its edits, its instances, and the mappings of its fields. NULL is ignored.
///
/// # Safety
/// `scene` must be NULL or a handle from `vlf_scene_create` not yet destroyed, not in use by
/// another call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_destroy(scene: *mut VlfScene) {
    if scene.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle from `Box::into_raw` in `vlf_scene_create`, destroyed once.
        drop(unsafe { Box::from_raw(scene) });
    }));
}

/// Opens (maps) the field file at `path` into the scene and writes its id to `*field` (0, 1, …
/// in the order fields are added). Every instance of the field shares the one mapping; add a file
/// once and place it as often as needed.
///
/// Returns `VLF_OK`, or what `vlf_open_path` returns for the file.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `path` NULL or NUL-terminated;
/// `field` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_add_field(scene: *mut VlfScene, path: *const c_char, field: *mut u32) -> VlfStatus {
    call("vlf_scene_add_field", || {
        // SAFETY: the caller's promises.
        let (scene, field) = unsafe { (scene_mut(scene)?, out(field, "field")?) };
        if path.is_null() {
            return Err(Failure::null("path"));
        }
        // SAFETY: non-null, NUL-terminated by the caller's promise.
        let bytes = unsafe { CStr::from_ptr(path) }.to_bytes();
        let f = OpenOptions::new().open(path_of(bytes)?)?;
        field.write(scene.add_field(EditedField::new(Arc::new(f))).0);
        Ok(())
    })
}

/// Places field `field` in the world with `transform` (16 doubles, a row-major 4×4 affine matrix
/// mapping the field's space to the world, last row `0 0 0 1`; NULL for the identity) and
/// `mask`, and writes the new instance's id to `*instance` (0, 1, … never reused). Costs
/// `O(log n)` for `n` instances, nothing proportional to the field's triangles.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for a field id the scene lacks or a transform that
/// is not finite, not affine, singular or out of range (the message says which); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `transform` NULL or 16 doubles;
/// `instance` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_add_instance(
    scene: *mut VlfScene,
    field: u32,
    transform: *const f64,
    mask: u32,
    instance: *mut u32,
) -> VlfStatus {
    call("vlf_scene_add_instance", || {
        // SAFETY: the caller's promises.
        let (scene, t, instance) =
            unsafe { (scene_mut(scene)?, transform_arg(transform, "transform")?, out(instance, "instance")?) };
        let id = field_id(scene, field)?;
        instance.write(scene.add_instance(id, t, mask)?);
        Ok(())
    })
}

/// One instance of `vlf_scene_add_instances`: the field to place (an id from
/// `vlf_scene_add_field`), its transform (16 doubles as in `vlf_scene_add_instance`; NULL for the
/// identity) and its mask.
#[repr(C)]
pub struct VlfInstanceDesc {
    /// The field's id in the scene.
    pub field: u32,
    /// The instance's mask: a query sees it only if their masks share a bit.
    pub mask: u32,
    /// 16 doubles, a row-major 4×4 affine matrix; NULL for the identity.
    pub transform: *const f64,
}

/// Places `n` instances at once: what `vlf_scene_add_instance` does once per instance, with the
/// top-level hierarchy built once over all of them when they are a quarter of the scene or more
/// (900,000 instances of a grid load in 5.0 s this way and in 9.4 s one call at a time:
/// `docs/dynamic.md`). They get the ids `*first`, `*first + 1`, …, in order.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for an instance of a field the scene lacks or
/// with an unusable transform (the message names the instance; nothing is placed);
/// `VLF_ERR_LIMIT` past 2³² − 1 instances; `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `instances` must point to `n`
/// descriptions, each `transform` NULL or pointing to 16 doubles; `first` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_add_instances(
    scene: *mut VlfScene,
    instances: *const VlfInstanceDesc,
    n: usize,
    first: *mut u32,
) -> VlfStatus {
    call("vlf_scene_add_instances", || {
        // SAFETY: the caller's promises on `scene`, `instances` and `first`.
        let (scene, descs, first) =
            unsafe { (scene_mut(scene)?, slice_arg(instances, n, "instances")?, optional_out(first, "first")?) };
        let mut placed = Vec::with_capacity(n);
        for (i, d) in descs.iter().enumerate() {
            // SAFETY: the caller's promise on each transform.
            let t = unsafe { transform_arg(d.transform, &format!("instances[{i}].transform")) }?;
            placed.push((FieldId(d.field), t, d.mask));
        }
        // The scene checks the field ids, all before placing any.
        let ids = scene.add_instances(&placed).map_err(|(i, e)| Failure::from(e).about(&format!("instances[{i}]")))?;
        if let Some(first) = first {
            first.write(ids.start);
        }
        Ok(())
    })
}

/// Moves instance `instance`: `transform` (as in `vlf_scene_add_instance`) replaces its
/// transform. Refits the top-level hierarchy along the instance's path: nothing proportional to
/// its triangles.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for an instance the scene lacks or an unusable
/// transform; `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `transform` NULL or 16 doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_set_transform(
    scene: *mut VlfScene,
    instance: u32,
    transform: *const f64,
) -> VlfStatus {
    call("vlf_scene_set_transform", || {
        // SAFETY: the caller's promises.
        let (scene, t) = unsafe { (scene_mut(scene)?, transform_arg(transform, "transform")?) };
        Ok(scene.set_transform(instance, t)?)
    })
}

/// Sets instance `instance`'s mask: a query sees it only if their masks share a bit.
///
/// Returns `VLF_OK`, `VLF_ERR_INVALID_ARGUMENT` (no such instance) or `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_set_mask(scene: *mut VlfScene, instance: u32, mask: u32) -> VlfStatus {
    call("vlf_scene_set_mask", || {
        // SAFETY: the caller's promise.
        let scene = unsafe { scene_mut(scene) }?;
        Ok(scene.set_mask(instance, mask)?)
    })
}

/// Removes instance `instance` from the scene (its id is not reused).
///
/// Returns `VLF_OK`, `VLF_ERR_INVALID_ARGUMENT` (no such instance) or `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_remove_instance(scene: *mut VlfScene, instance: u32) -> VlfStatus {
    call("vlf_scene_remove_instance", || {
        // SAFETY: the caller's promise.
        let scene = unsafe { scene_mut(scene) }?;
        Ok(scene.remove_instance(instance)?)
    })
}

/// Removes the `n` triangles `ids` from field `field` (every instance of it loses them), in
/// memory: the file is not written. Ids already removed are skipped; `*removed` (if not NULL)
/// receives how many were removed now.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for a field the scene lacks, an id out of range or
/// a misaligned `removed` (then nothing is removed); `VLF_ERR_NULL_ARGUMENT` (`ids` may be NULL
/// when `n` is 0).
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `ids` must point to `n` ids;
/// `removed` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_remove_triangles(
    scene: *mut VlfScene,
    field: u32,
    ids: *const u32,
    n: usize,
    removed: *mut u64,
) -> VlfStatus {
    call("vlf_scene_remove_triangles", || {
        // SAFETY: the caller's promises.
        let (scene, ids, removed) =
            unsafe { (scene_mut(scene)?, slice_arg(ids, n, "ids")?, optional_out(removed, "removed")?) };
        let id = field_id(scene, field)?;
        let now = scene.edit(id, |f| f.remove(ids)).expect("checked field")?;
        if let Some(removed) = removed {
            removed.write(now);
        }
        Ok(())
    })
}

/// Removes from field `field` every triangle whose provenance name is `name` (a NUL-terminated
/// UTF-8 OBJ object or group name, or glTF mesh name), in memory. `*removed` (if not NULL)
/// receives how many were removed now.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if no triangle comes from `name` (the message
/// lists some of the field's names), the field is not the scene's or `removed` is misaligned
/// (then nothing is removed); `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `name` NULL or NUL-terminated;
/// `removed` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_remove_object(
    scene: *mut VlfScene,
    field: u32,
    name: *const c_char,
    removed: *mut u64,
) -> VlfStatus {
    call("vlf_scene_remove_object", || {
        // SAFETY: the caller's promises.
        let (scene, removed) = unsafe { (scene_mut(scene)?, optional_out(removed, "removed")?) };
        if name.is_null() {
            return Err(Failure::null("name"));
        }
        // SAFETY: non-null, NUL-terminated by the caller's promise.
        let name = unsafe { CStr::from_ptr(name) }
            .to_str()
            .map_err(|_| Failure::invalid("argument `name` is not valid UTF-8".into()))?;
        let id = field_id(scene, field)?;
        let now = scene.edit(id, |f| f.remove_object(Object::Name(name))).expect("checked field")?;
        if let Some(removed) = removed {
            removed.write(now);
        }
        Ok(())
    })
}

/// Inserts `n` triangles into field `field`, in memory: `vertices` holds 9 doubles per triangle
/// (`v0.x, v0.y, v0.z, v1.x, …, v2.z`) in the mesh's own space, placed in the field's space by
/// `transform` (16 doubles as in `vlf_scene_add_instance`; NULL for the identity), then
/// rasterised into the field's directions, tiles and leaves with the bake's kernel. Every
/// instance of the field shows them. `*first` receives the id of the first (the others follow in
/// order): ids after every id in use.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for a field the scene lacks, an unusable
/// transform, a vertex that is not finite or a triangle outside the field's bounding sphere
/// (then nothing is inserted); `VLF_ERR_LIMIT` past 2³² − 1 triangles; `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `vertices` must point to `9·n`
/// doubles; `transform` NULL or 16 doubles; `first` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_insert_triangles(
    scene: *mut VlfScene,
    field: u32,
    vertices: *const f64,
    n: usize,
    transform: *const f64,
    first: *mut u32,
) -> VlfStatus {
    call("vlf_scene_insert_triangles", || {
        let count = n.checked_mul(9).ok_or_else(|| Failure::invalid(format!("count {n} is too large")))?;
        // SAFETY: the caller's promises.
        let (scene, v, t, first) = unsafe {
            (
                scene_mut(scene)?,
                slice_arg(vertices, count, "vertices")?,
                transform_arg(transform, "transform")?,
                out(first, "first")?,
            )
        };
        let id = field_id(scene, field)?;
        let ids = scene.edit(id, |f| f.insert(&triangles_of(v), &t)).expect("checked field")?;
        first.write(ids.start);
        Ok(())
    })
}

/// Triangles from 9 doubles each (`v0.x, v0.y, v0.z, v1.x, …, v2.z`).
fn triangles_of(v: &[f64]) -> Vec<[[f64; 3]; 3]> {
    v.chunks_exact(9).map(|c| std::array::from_fn(|k| [c[3 * k], c[3 * k + 1], c[3 * k + 2]])).collect()
}

/// One mesh of `vlf_scene_insert_meshes`: `triangle_count` triangles at `vertices`, 9 doubles
/// each as in `vlf_scene_insert_triangles`, placed by `transform` (16 doubles as in
/// `vlf_scene_add_instance`; NULL for the identity).
#[repr(C)]
pub struct VlfMesh {
    /// `9 · triangle_count` doubles (may be NULL when `triangle_count` is 0).
    pub vertices: *const f64,
    /// The number of triangles.
    pub triangle_count: usize,
    /// 16 doubles, a row-major 4×4 affine matrix; NULL for the identity.
    pub transform: *const f64,
}

/// Inserts `n` meshes into field `field`, in memory, each placed by its own transform: what
/// `vlf_scene_insert_triangles` does once per mesh, with the field's tiles rebuilt once for all
/// of them instead of once per call (a thousand small meshes inserted one call at a time rebuild
/// the tiles they share a thousand times). `firsts[i]` receives the id of mesh `i`'s first
/// triangle (its others follow in order, and each mesh's ids follow the previous mesh's).
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` for a field the scene lacks, or for a mesh with an
/// unusable transform, a vertex that is not finite or a triangle outside the field's bounding
/// sphere (the message names the mesh, `meshes[i]`, and the triangle; nothing is inserted);
/// `VLF_ERR_LIMIT` past 2³² − 1 triangles; `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle used by no other call; `meshes` must point to `n`
/// meshes, each with `vertices` pointing to `9 · triangle_count` doubles and `transform` NULL or
/// pointing to 16 doubles; `firsts` NULL or room for `n` ids.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_insert_meshes(
    scene: *mut VlfScene,
    field: u32,
    meshes: *const VlfMesh,
    n: usize,
    firsts: *mut u32,
) -> VlfStatus {
    call("vlf_scene_insert_meshes", || {
        check_array(meshes, n, "meshes")?;
        if !firsts.is_null() {
            check_array(firsts, n, "firsts")?;
            check_disjoint(span(meshes, n), span(firsts, n), "arrays `meshes` and `firsts`")?;
        }
        // SAFETY: the caller's promises on `scene` and `meshes`.
        let (scene, meshes) = unsafe { (scene_mut(scene)?, slice_arg(meshes, n, "meshes")?) };
        let id = field_id(scene, field)?;
        let mut parts = Vec::with_capacity(n);
        for (i, mesh) in meshes.iter().enumerate() {
            let count = mesh
                .triangle_count
                .checked_mul(9)
                .ok_or_else(|| Failure::invalid(format!("meshes[{i}]: count {} is too large", mesh.triangle_count)))?;
            // SAFETY: the caller's promises on each mesh's arrays.
            let (v, t) = unsafe {
                (
                    slice_arg(mesh.vertices, count, &format!("meshes[{i}].vertices"))?,
                    transform_arg(mesh.transform, &format!("meshes[{i}].transform"))?,
                )
            };
            parts.push((triangles_of(v), t));
        }
        let borrowed: Vec<(&[[[f64; 3]; 3]], &Affine)> = parts.iter().map(|(v, t)| (v.as_slice(), t)).collect();
        let ranges = scene.edit(id, |f| f.insert_all(&borrowed)).expect("checked field").map_err(|(i, e)| match e {
            // Faults of the whole insert, not of one mesh.
            EditError::TooManyTriangles | EditError::TooLarge => Failure::from(e),
            _ => Failure::from(e).about(&format!("meshes[{i}]")),
        })?;
        if !firsts.is_null() {
            // SAFETY: room for `n` ids by the caller's promise (checked non-null and aligned);
            // written only now that the insert succeeded.
            let firsts = unsafe { slice_out(firsts, n, "firsts")? };
            write_all(firsts, &ranges.iter().map(|r| r.start).collect::<Vec<u32>>());
        }
        Ok(())
    })
}

/// Traces `ray` through the instances whose mask shares a bit with `mask`: writes its closest
/// hit on `[tmin, tmax]` to `*hit` (`prim` the triangle's id in the hit instance's field,
/// inserted triangles after the field's own; `t` in units of the world ray) and the instance to
/// `*instance` (`VLF_NO_INSTANCE` and the miss record if nothing is hit). The same answer, bit for
/// bit, as the Rust `Scene::closest_hit`. Allocates nothing.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT` or `VLF_ERR_INVALID_ARGUMENT`
/// (misaligned or overlapping pointers).
///
/// # Safety
/// `scene` must be NULL or a live handle; `ray` NULL or a valid ray; `hit` and `instance` NULL or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_closest_hit(
    scene: *const VlfScene,
    ray: *const VlfRay,
    mask: u32,
    hit: *mut VlfHit,
    instance: *mut u32,
) -> VlfStatus {
    call("vlf_scene_closest_hit", || {
        check_array(hit, 1, "hit")?;
        check_array(instance, 1, "instance")?;
        check_disjoint(span(hit, 1), span(instance, 1), "arguments `hit` and `instance`")?;
        // SAFETY: the caller's promises, argument by argument; the outputs do not overlap.
        let (scene, ray, hit, instance) =
            unsafe { (scene_arg(scene)?, arg(ray, "ray")?, out(hit, "hit")?, out(instance, "instance")?) };
        let h = scene.closest_hit(bytemuck::cast_ref(ray), mask);
        hit.write(bytemuck::cast(Hit::record(h.map(|h| h.hit))));
        instance.write(h.map_or(VLF_NO_INSTANCE, |h| h.instance));
        Ok(())
    })
}

/// Traces `ray` for any hit on `[tmin, tmax]` among the instances whose mask shares a bit with
/// `mask`: writes 1 to `*hit` if something is hit, 0 if not.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT` or `VLF_ERR_INVALID_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle; `ray` NULL or a valid ray; `hit` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_any_hit(
    scene: *const VlfScene,
    ray: *const VlfRay,
    mask: u32,
    hit: *mut u8,
) -> VlfStatus {
    call("vlf_scene_any_hit", || {
        // SAFETY: the caller's promises, argument by argument.
        let (scene, ray, hit) = unsafe { (scene_arg(scene)?, arg(ray, "ray")?, out(hit, "hit")?) };
        hit.write(scene.any_hit(bytemuck::cast_ref(ray), mask) as u8);
        Ok(())
    })
}

/// Traces `n` rays as `vlf_scene_closest_hit` would: `hits[i]` and `instances[i]` receive the
/// answer for `rays[i]`. Runs on the calling thread; call it from several threads on disjoint
/// parts of the arrays to use several cores. `rays`, `hits` and `instances` may be NULL when `n`
/// is 0, and must not overlap.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (misaligned or
/// overlapping arrays, or `n` too large); on an error nothing is written.
///
/// # Safety
/// `scene` must be NULL or a live handle; `rays` must point to `n` rays, `hits` to room for `n`
/// hits and `instances` to room for `n` ids (or be NULL when `n` is 0).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_closest_hits(
    scene: *const VlfScene,
    rays: *const VlfRay,
    n: usize,
    mask: u32,
    hits: *mut VlfHit,
    instances: *mut u32,
) -> VlfStatus {
    call("vlf_scene_closest_hits", || {
        // SAFETY: the caller's promise on `scene`.
        let scene = unsafe { scene_arg(scene) }?;
        check_array(rays, n, "rays")?;
        check_array(hits, n, "hits")?;
        check_array(instances, n, "instances")?;
        check_disjoint(span(rays, n), span(hits, n), "arrays `rays` and `hits`")?;
        check_disjoint(span(rays, n), span(instances, n), "arrays `rays` and `instances`")?;
        check_disjoint(span(hits, n), span(instances, n), "arrays `hits` and `instances`")?;
        // SAFETY: the caller's promises on the arrays; they do not overlap (checked).
        let (rays, hits, instances) = unsafe {
            (slice_arg(rays, n, "rays")?, slice_out(hits, n, "hits")?, slice_out(instances, n, "instances")?)
        };
        for ((ray, hit), instance) in rays.iter().zip(hits).zip(instances) {
            let h = scene.closest_hit(bytemuck::cast_ref(ray), mask);
            hit.write(bytemuck::cast(Hit::record(h.map(|h| h.hit))));
            instance.write(h.map_or(VLF_NO_INSTANCE, |h| h.instance));
        }
        Ok(())
    })
}

/// The number of instances in the scene (added and not removed), in `*count`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT` or `VLF_ERR_INVALID_ARGUMENT`.
///
/// # Safety
/// `scene` must be NULL or a live handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_scene_instance_count(scene: *const VlfScene, count: *mut u32) -> VlfStatus {
    call("vlf_scene_instance_count", || {
        // SAFETY: the caller's promises.
        let (scene, count) = unsafe { (scene_arg(scene)?, out(count, "count")?) };
        count.write(count_u32(scene.instance_count()));
        Ok(())
    })
}
