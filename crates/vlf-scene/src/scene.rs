//! A scene of instances: fields placed by affine transforms, each with an id and a mask, under a
//! top-level hierarchy over their world boxes (the private `bvh` module).
//!
//! A ray is tested against the hierarchy in world space; for each instance whose box it enters
//! (nearest first), whose mask it shares a bit with, it is moved into the instance's field (the
//! inverse transform, then relative to the field's centre, computed in f64 and rounded to the
//! f32 of a [`Ray`]) and answered by that field with its edits. The transformed ray keeps the
//! world ray's parameter: `o + t·d` maps to `o' + t·d'`, so a hit's `t` is in the units of the
//! world ray, and a closest-hit search passes its best `t` on as the next instance's `tmax`.

use crate::affine::Affine;
use crate::bvh::{Aabb, BoxRay, Bvh};
use crate::edit::EditedField;
use std::cell::Cell;
use std::sync::Arc;
use vlf_geom::{Counter, Hit, Intersector, Ray, TraceStats};
use vlf_runtime::Field;

/// A field of a scene: an index into [`Scene::fields`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FieldId(pub u32);

/// The id of an instance, given by [`Scene::add_instance`] in order from 0 and never reused.
pub type InstanceId = u32;

/// A hit in a scene: the hit in the instance's field (`prim` is the triangle's id in that field,
/// inserted triangles numbered after the field's own; `t` in units of the world ray) and the
/// instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneHit {
    /// The hit in the instance's field, `t` in units of the world ray.
    pub hit: Hit,
    /// The instance hit.
    pub instance: InstanceId,
}

/// Why a scene refused a change. Nothing changed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// A field id the scene does not have (the id, and how many fields there are).
    #[error("there is no field {0} in the scene (it has {1})")]
    NoSuchField(u32, usize),
    /// An instance id the scene does not have (never added, or removed).
    #[error("there is no instance {0} in the scene")]
    NoSuchInstance(InstanceId),
    /// Instance ids are `u32`, `0xFFFFFFFF` excepted (it means a miss).
    #[error("the scene would have more than 2^32 - 1 instances")]
    TooManyInstances,
    /// [`Scene::flat`]'s numbers would not fit in `u32`.
    #[error("the scene's instances have more than 2^32 - 1 triangle ids in all")]
    TooManyTriangles,
}

/// One placed field.
#[derive(Clone, Copy, Debug)]
struct Instance {
    field: FieldId,
    transform: Affine,
    /// World → the field's coordinates relative to its centre.
    to_local: Affine,
    mask: u32,
}

/// What an instance is, for callers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceInfo {
    /// The field it places.
    pub field: FieldId,
    /// Maps the field's space to the world.
    pub transform: Affine,
    /// Rays whose mask shares no bit with it do not see it.
    pub mask: u32,
}

/// Fields placed by transforms, with edits, answering closest-hit and any-hit queries.
///
/// Queries take `&self` and a `Scene` is `Send + Sync`: any number of threads may query at once.
/// Changes take `&mut self`.
#[derive(Default)]
pub struct Scene {
    fields: Vec<EditedField>,
    instances: Vec<Option<Instance>>,
    live: usize,
    bvh: Bvh,
}

/// The box of `field`'s live triangles moved by `transform`, or `None` if it has none.
fn content_box(field: &EditedField, transform: &Affine) -> Option<([f64; 3], [f64; 3])> {
    let (lo, hi) = field.bounds_local();
    if !(0..3).all(|k| lo[k] <= hi[k]) {
        return None;
    }
    let c = field.field().origin();
    Some(transform.bounds(std::array::from_fn(|k| lo[k] + c[k]), std::array::from_fn(|k| hi[k] + c[k])))
}

/// [`content_box`] grown by a relative 2⁻²⁰ so that the rounding of the transformed ray can
/// never take a hit outside it: the box the hierarchy holds.
fn world_box(field: &EditedField, transform: &Affine) -> Aabb {
    let Some((lo, hi)) = content_box(field, transform) else { return Aabb::EMPTY };
    let size = (0..3).map(|k| (hi[k] - lo[k]) + lo[k].abs().max(hi[k].abs())).fold(0.0, f64::max);
    let grow = size * (1.0 / (1u64 << 20) as f64);
    Aabb { lo: lo.map(|v| v - grow), hi: hi.map(|v| v + grow) }
}

impl Instance {
    fn new(field: FieldId, transform: Affine, mask: u32, origin: [f64; 3]) -> Instance {
        let inv = transform.inverse();
        let mut rows = inv.rows();
        for k in 0..3 {
            rows[k][3] -= origin[k];
        }
        let to_local = Affine::from_3x4(rows).unwrap_or(inv);
        Instance { field, transform, to_local, mask }
    }

    /// The world ray in the field's coordinates relative to its centre, on `[tmin, tmax]`.
    #[inline]
    /// The ray whose world origin is `org` (in f64) and whose direction and `tmin` are `ray`'s,
    /// in this instance's field relative to its centre: mapped in f64, then rounded to f32.
    fn local_ray(&self, org: [f64; 3], ray: &Ray, tmax: f32) -> Ray {
        let o = self.to_local.point(org).map(|v| v as f32);
        let d = self.to_local.vector(ray.dir.map(f64::from)).map(|v| v as f32);
        Ray { org: o, tmin: ray.tmin, dir: d, tmax }
    }
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Scene {
        Scene { bvh: Bvh::new(), ..Scene::default() }
    }

    /// Adds a field (mapped once, shared by every instance of it) and returns its id.
    pub fn add_field(&mut self, field: impl Into<EditedField>) -> FieldId {
        self.fields.push(field.into());
        FieldId(self.fields.len() as u32 - 1)
    }

    /// The scene's fields, by id.
    pub fn fields(&self) -> &[EditedField] {
        &self.fields
    }

    /// Field `id` and its edits.
    pub fn field(&self, id: FieldId) -> Option<&EditedField> {
        self.fields.get(id.0 as usize)
    }

    /// Edits field `id` with `edit` (shown by every instance of it), then refits those
    /// instances' boxes. `None` if there is no such field.
    pub fn edit<R>(&mut self, id: FieldId, edit: impl FnOnce(&mut EditedField) -> R) -> Option<R> {
        let r = edit(self.fields.get_mut(id.0 as usize)?);
        let f = &self.fields[id.0 as usize];
        for (k, i) in self.instances.iter().enumerate() {
            if let Some(i) = i.filter(|i| i.field == id) {
                self.bvh.update(k as u32, world_box(f, &i.transform));
            }
        }
        self.bvh.maybe_rebuild();
        Some(r)
    }

    /// Places field `field` in the world with `transform` (the field's space to the world) and
    /// `mask`, and returns the new instance's id. `O(depth)` of the hierarchy.
    ///
    /// # Errors
    /// [`SceneError::NoSuchField`], [`SceneError::TooManyInstances`].
    pub fn add_instance(&mut self, field: FieldId, transform: Affine, mask: u32) -> Result<InstanceId, SceneError> {
        self.add_instances(&[(field, transform, mask)]).map(|ids| ids.start).map_err(|(_, e)| e)
    }

    /// [`Scene::add_instance`] of many instances at once, in order: their ids are consecutive
    /// (returned as a range). When they are many against the instances already placed (a quarter
    /// of them or more), the hierarchy is built once over all of them, `O(n log n)`, instead of
    /// taking each in turn (each insert `O(depth)`, with the subtree rebuilds and the geometric
    /// whole-tree rebuilds of the area rule they bring: 900,000 instances of a grid take 1.9
    /// times as long one at a time, `docs/dynamic.md`). Either all are added or none.
    ///
    /// # Errors
    /// [`SceneError::NoSuchField`] or [`SceneError::TooManyInstances`], with the index of the
    /// first instance at fault; nothing is added.
    pub fn add_instances(
        &mut self,
        instances: &[(FieldId, Affine, u32)],
    ) -> Result<std::ops::Range<InstanceId>, (usize, SceneError)> {
        let first = self.instances.len();
        if let Some(k) = instances.iter().position(|(f, _, _)| self.fields.get(f.0 as usize).is_none()) {
            return Err((k, SceneError::NoSuchField(instances[k].0.0, self.fields.len())));
        }
        // Ids stop below u32::MAX (the id of a miss).
        let room = (u32::MAX as usize).saturating_sub(first);
        if instances.len() > room {
            return Err((room, SceneError::TooManyInstances));
        }
        if instances.is_empty() {
            return Ok(first as u32..first as u32);
        }
        let whole = instances.len() >= self.live / 4;
        let mut boxes = Vec::with_capacity(instances.len());
        for (k, &(field, transform, mask)) in instances.iter().enumerate() {
            let f = &self.fields[field.0 as usize];
            boxes.push(((first + k) as u32, world_box(f, &transform)));
            self.instances.push(Some(Instance::new(field, transform, mask, f.field().origin())));
        }
        self.live += instances.len();
        if whole {
            let mut items = self.bvh.items();
            items.extend(boxes);
            self.bvh.build(&items);
        } else {
            for (key, b) in boxes {
                self.bvh.insert(key, b);
            }
            self.bvh.maybe_rebuild();
        }
        Ok(first as u32..self.instances.len() as u32)
    }

    fn instance_mut(&mut self, id: InstanceId) -> Result<&mut Instance, SceneError> {
        self.instances.get_mut(id as usize).and_then(Option::as_mut).ok_or(SceneError::NoSuchInstance(id))
    }

    /// Moves instance `id`: its new transform maps its field's space to the world. Refits the
    /// hierarchy along the instance's path, `O(depth)`, whatever the field holds.
    ///
    /// # Errors
    /// [`SceneError::NoSuchInstance`].
    pub fn set_transform(&mut self, id: InstanceId, transform: Affine) -> Result<(), SceneError> {
        let i = *self.instance_mut(id)?;
        let f = &self.fields[i.field.0 as usize];
        let moved = Instance::new(i.field, transform, i.mask, f.field().origin());
        let b = world_box(f, &transform);
        *self.instance_mut(id)? = moved;
        self.bvh.update(id, b);
        self.bvh.maybe_rebuild();
        Ok(())
    }

    /// Sets instance `id`'s mask: a ray sees it only if their masks share a bit.
    ///
    /// # Errors
    /// [`SceneError::NoSuchInstance`].
    pub fn set_mask(&mut self, id: InstanceId, mask: u32) -> Result<(), SceneError> {
        self.instance_mut(id)?.mask = mask;
        Ok(())
    }

    /// Removes instance `id` (its id is not reused).
    ///
    /// # Errors
    /// [`SceneError::NoSuchInstance`].
    pub fn remove_instance(&mut self, id: InstanceId) -> Result<(), SceneError> {
        self.instance_mut(id)?;
        self.instances[id as usize] = None;
        self.live -= 1;
        self.bvh.remove(id);
        self.bvh.maybe_rebuild();
        Ok(())
    }

    /// Rebuilds the hierarchy from scratch, `O(n log n)` for `n` instances (changes rebuild it
    /// when it has degraded; call this after adding many instances, before querying).
    pub fn rebuild(&mut self) {
        let items = self.bvh.items();
        self.bvh.build(&items);
    }

    /// How many times the hierarchy was built from scratch.
    pub fn rebuilds(&self) -> u64 {
        self.bvh.builds
    }

    /// Instance `id`, if it exists.
    pub fn instance(&self, id: InstanceId) -> Option<InstanceInfo> {
        let i = self.instances.get(id as usize)?.as_ref()?;
        Some(InstanceInfo { field: i.field, transform: i.transform, mask: i.mask })
    }

    /// The ids of the instances, increasing.
    pub fn instance_ids(&self) -> impl Iterator<Item = InstanceId> + '_ {
        self.instances.iter().enumerate().filter(|(_, i)| i.is_some()).map(|(k, _)| k as InstanceId)
    }

    /// The number of instances.
    pub fn instance_count(&self) -> usize {
        self.live
    }

    /// The box around every instance's live triangles, in world coordinates (empty: `lo > hi`).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let b = self.bvh.bounds();
        (b.lo, b.hi)
    }

    /// The box of every instance's live triangles in world coordinates, not grown as the
    /// hierarchy's boxes are ([`Scene::bounds`]): what a camera frames. Empty (`lo > hi`) if
    /// there are none. Time linear in the instances.
    pub fn content_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for i in self.instances.iter().flatten() {
            if let Some((l, h)) = content_box(&self.fields[i.field.0 as usize], &i.transform) {
                for k in 0..3 {
                    (lo[k], hi[k]) = (lo[k].min(l[k]), hi[k].max(h[k]));
                }
            }
        }
        (lo, hi)
    }

    /// The box around instance `id`'s live triangles in world coordinates, as the hierarchy
    /// holds it (grown by a relative 2⁻²⁰), or `None` if there is no such instance.
    pub fn instance_bounds(&self, id: InstanceId) -> Option<([f64; 3], [f64; 3])> {
        let i = self.instances.get(id as usize)?.as_ref()?;
        let b = world_box(&self.fields[i.field.0 as usize], &i.transform);
        Some((b.lo, b.hi))
    }

    /// The vertices of triangle `prim` of instance `instance` in world coordinates, or `None`
    /// if there is no such instance or triangle, or it was removed.
    pub fn world_triangle(&self, instance: InstanceId, prim: u32) -> Option<[[f64; 3]; 3]> {
        let i = self.instances.get(instance as usize)?.as_ref()?;
        let f = &self.fields[i.field.0 as usize];
        let c = f.field().origin();
        let t = f.triangle_local(prim)?;
        Some(t.map(|v| i.transform.point(std::array::from_fn(|k| v[k] as f64 + c[k]))))
    }

    /// The world ray `ray` in instance `id`'s field, relative to the field's centre, exactly as
    /// the queries hand it to the field (mapped in f64, rounded to f32; `t` keeps its meaning),
    /// or `None` if there is no such instance. With [`EditedField::triangle_local`], a brute
    /// force over one instance that agrees with the scene bit for bit.
    pub fn local_ray(&self, id: InstanceId, ray: &Ray) -> Option<Ray> {
        Some(self.instances.get(id as usize)?.as_ref()?.local_ray(ray.org.map(f64::from), ray, ray.tmax))
    }

    /// The closest hit of `ray` on `[tmin, tmax]` among the instances whose mask shares a bit
    /// with `mask`, or `None` (a miss, or an invalid ray).
    pub fn closest_hit(&self, ray: &Ray, mask: u32) -> Option<SceneHit> {
        self.closest_hit_counted(ray, mask, &mut ())
    }

    /// Whether `ray` hits anything on `[tmin, tmax]` among the instances whose mask shares a bit
    /// with `mask`; stops at the first hit found.
    pub fn any_hit(&self, ray: &Ray, mask: u32) -> bool {
        self.any_hit_counted(ray, mask, &mut ()).is_some()
    }

    /// [`Scene::closest_hit`], counting the work: the hierarchy's nodes as cells, then each
    /// field's tiles, leaves and triangle tests (a ray counts once per instance it reaches).
    pub fn closest_hit_counted(&self, ray: &Ray, mask: u32, counter: &mut impl Counter) -> Option<SceneHit> {
        self.closest_hit_from([0.0; 3], ray, mask, counter)
    }

    /// [`Scene::closest_hit_counted`] for a ray whose origin is given relative to `origin` (in
    /// f64): the world ray starts at `origin + ray.org`. A scene far from the world's origin is
    /// traced exactly this way (f32 world coordinates there are too coarse for its rays), as
    /// [`Flat`] does for the renderer; `t` means what it means for the world ray.
    pub fn closest_hit_from(
        &self,
        origin: [f64; 3],
        ray: &Ray,
        mask: u32,
        counter: &mut impl Counter,
    ) -> Option<SceneHit> {
        if !ray.is_valid() {
            return None;
        }
        let org: [f64; 3] = std::array::from_fn(|k| origin[k] + ray.org[k] as f64);
        let br = BoxRay::new(org, ray.dir.map(f64::from), ray.tmin as f64);
        let tmax = Cell::new(ray.tmax);
        let mut best = None;
        self.bvh.traverse(
            &br,
            || tmax.get() as f64,
            counter,
            |k, counter| {
                let Some(i) = self.instances.get(k as usize).and_then(Option::as_ref) else { return false };
                if i.mask & mask == 0 {
                    return false;
                }
                let local = i.local_ray(org, ray, tmax.get());
                if let Some(hit) = self.fields[i.field.0 as usize].closest_hit_local(&local, counter) {
                    tmax.set(hit.t);
                    best = Some(SceneHit { hit, instance: k });
                }
                false
            },
        );
        best
    }

    /// [`Scene::any_hit`], returning the hit it found and counting the work.
    pub fn any_hit_counted(&self, ray: &Ray, mask: u32, counter: &mut impl Counter) -> Option<SceneHit> {
        self.any_hit_from([0.0; 3], ray, mask, counter)
    }

    /// [`Scene::any_hit_counted`] for a ray whose origin is given relative to `origin`, as
    /// [`Scene::closest_hit_from`].
    pub fn any_hit_from(&self, origin: [f64; 3], ray: &Ray, mask: u32, counter: &mut impl Counter) -> Option<SceneHit> {
        if !ray.is_valid() {
            return None;
        }
        let org: [f64; 3] = std::array::from_fn(|k| origin[k] + ray.org[k] as f64);
        let br = BoxRay::new(org, ray.dir.map(f64::from), ray.tmin as f64);
        let mut found = None;
        self.bvh.traverse(
            &br,
            || ray.tmax as f64,
            counter,
            |k, counter| {
                let Some(i) = self.instances.get(k as usize).and_then(Option::as_ref) else { return false };
                if i.mask & mask == 0 {
                    return false;
                }
                let local = i.local_ray(org, ray, ray.tmax);
                found = self.fields[i.field.0 as usize]
                    .any_hit_local(&local, counter)
                    .map(|hit| SceneHit { hit, instance: k });
                found.is_some()
            },
        );
        found
    }

    /// The scene with one number per (instance, triangle), for code that knows triangles by a
    /// single id (the renderer): instances in id order, each taking its field's id range.
    ///
    /// # Errors
    /// [`SceneError::TooManyTriangles`] if the numbers would pass 2³² − 1.
    pub fn flat(&self) -> Result<Flat<'_>, SceneError> {
        let mut starts = vec![u32::MAX; self.instances.len()];
        let mut next = 0u64;
        let mut order = Vec::with_capacity(self.live);
        for k in self.instance_ids() {
            let i = self.instances[k as usize].as_ref().expect("live");
            starts[k as usize] = u32::try_from(next).map_err(|_| SceneError::TooManyTriangles)?;
            order.push((next as u32, k));
            next += self.fields[i.field.0 as usize].id_count() as u64;
        }
        if next > u32::MAX as u64 {
            return Err(SceneError::TooManyTriangles);
        }
        let (lo, hi) = self.content_bounds();
        let origin =
            if (0..3).all(|k| lo[k] <= hi[k]) { std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])) } else { [0.0; 3] };
        Ok(Flat { scene: self, starts, order, count: next as u32, origin })
    }
}

/// A scene seen as one set of triangles numbered `0..count` ([`Scene::flat`]); it answers as a
/// [`vlf_geom::Intersector`] over every instance (mask `0xFFFFFFFF`), a hit's `prim` being that
/// number. Its origin ([`Intersector::origin`]) is the centre of the scene's content
/// ([`Scene::content_bounds`]): rays given relative to it keep the precision of the scene's own
/// size however far it lies from the world's origin.
pub struct Flat<'a> {
    scene: &'a Scene,
    /// Per instance id, its first number (`u32::MAX` for a removed instance).
    starts: Vec<u32>,
    /// `(first number, instance)`, increasing.
    order: Vec<(u32, InstanceId)>,
    count: u32,
    /// The centre of the scene's content: what rays are given relative to
    /// ([`Intersector::origin`]).
    origin: [f64; 3],
}

impl Flat<'_> {
    /// How many numbers there are: the sum over instances of their fields' id counts.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The number of `prim` of `instance`.
    pub fn number(&self, instance: InstanceId, prim: u32) -> Option<u32> {
        self.starts.get(instance as usize).filter(|&&s| s != u32::MAX).map(|s| s + prim)
    }

    /// The instance and triangle a number stands for.
    pub fn resolve(&self, number: u32) -> Option<(InstanceId, u32)> {
        let at = self.order.partition_point(|&(start, _)| start <= number).checked_sub(1)?;
        let (start, k) = self.order[at];
        Some((k, number - start))
    }

    fn record(&self, h: SceneHit) -> Hit {
        Hit { prim: self.starts[h.instance as usize] + h.hit.prim, ..h.hit }
    }
}

impl Intersector for Flat<'_> {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.scene.closest_hit(ray, u32::MAX).map(|h| self.record(h))
    }
    fn any_hit(&self, ray: &Ray) -> bool {
        self.scene.any_hit(ray, u32::MAX)
    }
    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.scene.closest_hit_counted(ray, u32::MAX, work).map(|h| self.record(h))
    }
    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.scene.any_hit_counted(ray, u32::MAX, work).map(|h| self.record(h))
    }
    fn origin(&self) -> [f64; 3] {
        self.origin
    }
    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.scene.closest_hit_from(self.origin, ray, u32::MAX, work).map(|h| self.record(h))
    }
    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.scene.any_hit_from(self.origin, ray, u32::MAX, work).map(|h| self.record(h))
    }
}

impl From<Arc<Field>> for EditedField {
    fn from(field: Arc<Field>) -> EditedField {
        EditedField::new(field)
    }
}

impl From<Field> for EditedField {
    fn from(field: Field) -> EditedField {
        EditedField::new(Arc::new(field))
    }
}

#[allow(dead_code)]
fn assert_send_sync() {
    fn is<T: Send + Sync>() {}
    is::<Scene>();
}
