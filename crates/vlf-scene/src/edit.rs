//! A mapped field with edits (the paper's §7): triangles removed, by id or by where they came
//! from, and triangles inserted, all in memory. The file is never written: its mapped bytes stay
//! untouched and shared, and a query answers from them and from the edits together. Saving an
//! edited field is a new bake of its meshes.
//!
//! - **Removing** a triangle of the mapped field marks its id in a bitset; the query's leaf
//!   kernel reads the triangles through it and skips marked ids, exactly as it skips ids that a
//!   damaged file names (`vlf_geom::Triangles`). The ids stay in the mapped leaves (they cannot be
//!   written), so removed triangles still cost a box test where they were.
//! - **Inserting** triangles rasterises them into the field's directions, tiles and leaves with
//!   the bake's kernel, in an overlay kept beside the mapped bytes (the private `overlay` module); they get
//!   the ids after the field's own, in order, never reused. Removing an inserted triangle removes
//!   it from the overlay's tiles the paper's way (rasterised again, its id taken out).
//! - **Moving** an object is removing it and inserting it transformed.
//!
//! Inserted triangles must lie inside the field's bounding sphere: the field's tiles cover
//! nothing beyond it. (Place geometry anywhere with instances instead: [`crate::Scene`].)

// `!(a <= b)` is meant: it is true when either side is NaN, which must fail the test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::affine::Affine;
use crate::overlay::{Overlay, TooLarge};
use std::ops::Range;
use std::sync::Arc;
use vlf_format::{NO_INDEX, TriangleRecord};
use vlf_geom::{Closest, Counter, Hit, Ray, Triangles};
use vlf_runtime::Field;

/// Why an edit was refused. Nothing changed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EditError {
    /// A triangle id that the field does not have.
    #[error("triangle id {id} is out of range: the field has ids 0 to {}", .count.saturating_sub(1))]
    NoSuchTriangle {
        /// The id asked for.
        id: u32,
        /// The ids in use.
        count: u32,
    },
    /// No triangle's provenance matches.
    #[error("no triangle comes from {what} (the field's objects: {known})")]
    NoMatch {
        /// What was asked for.
        what: String,
        /// Some of the field's object names, for the message.
        known: String,
    },
    /// An inserted triangle has a vertex that is not finite once transformed.
    #[error("inserted triangle {triangle} has a vertex that is not a finite number once transformed")]
    NotFinite {
        /// The triangle's index in the inserted mesh.
        triangle: usize,
    },
    /// An inserted triangle reaches outside the field's bounding sphere.
    #[error(
        "inserted triangle {triangle} reaches {distance:.6} from the field's centre, outside its bounding sphere of radius {radius:.6}: \
         a field's tiles cover only its sphere (add the mesh as an instance of a field of its own instead)"
    )]
    OutsideSphere {
        /// The triangle's index in the inserted mesh.
        triangle: usize,
        /// Its farthest vertex's distance from the field's centre.
        distance: f64,
        /// The field's bounding sphere's radius.
        radius: f64,
    },
    /// The ids would pass 2³² − 1.
    #[error("the field would have more than 4294967295 triangles")]
    TooManyTriangles,
    /// The overlay's blocks would pass the format's 32-bit word offsets.
    #[error("the inserted triangles' tiles would take more than 2^32 words")]
    TooLarge,
}

/// Which triangles of a mapped field to remove, by their provenance (`formats/vlf.md` §5.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Object<'a> {
    /// Every source with this name: an OBJ object or group, or a glTF mesh.
    Name(&'a str),
    /// OBJ: the model index in file order; glTF: the mesh index.
    Mesh(u32),
    /// A glTF node.
    Node(u32),
}

impl std::fmt::Display for Object<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Object::Name(n) => write!(f, "an object named {n:?}"),
            Object::Mesh(m) => write!(f, "mesh {m}"),
            Object::Node(n) => write!(f, "glTF node {n}"),
        }
    }
}

/// A mapped field and its edits. Cheap to create; costs nothing until edited.
pub struct EditedField {
    base: Arc<Field>,
    /// One bit per id (the field's, then the inserted ones): removed.
    removed: Vec<u64>,
    removed_count: u64,
    /// Of those, the mapped field's own.
    removed_base: u64,
    overlay: Option<Overlay>,
}

/// The field's triangles as the kernel reads them, removed ones hidden.
struct Kept<'a> {
    tris: &'a [TriangleRecord],
    removed: &'a [u64],
}

#[inline(always)]
fn bit(bits: &[u64], id: u32) -> bool {
    bits.get(id as usize >> 6).is_some_and(|w| w >> (id & 63) & 1 != 0)
}

impl Triangles for Kept<'_> {
    #[inline(always)]
    fn vertices(&self, id: u32) -> Option<&[[f32; 3]; 3]> {
        if bit(self.removed, id) {
            return None;
        }
        Some(&self.tris.get(id as usize)?.v)
    }

    #[inline(always)]
    fn count(&self) -> usize {
        self.tris.len()
    }
}

impl EditedField {
    /// The field, unedited.
    pub fn new(field: Arc<Field>) -> EditedField {
        EditedField { base: field, removed: Vec::new(), removed_count: 0, removed_base: 0, overlay: None }
    }

    /// The mapped field.
    pub fn field(&self) -> &Arc<Field> {
        &self.base
    }

    /// The ids in use: the field's triangles, then the inserted ones (removed ones included).
    pub fn id_count(&self) -> u32 {
        self.base.triangle_count() + self.inserted_count()
    }

    /// The triangles inserted so far (removed ones included).
    pub fn inserted_count(&self) -> u32 {
        self.overlay.as_ref().map_or(0, |o| o.sections().triangles.len() as u32)
    }

    /// The triangles not removed.
    pub fn live_count(&self) -> u64 {
        self.id_count() as u64 - self.removed_count
    }

    /// Whether any edit was made.
    pub fn is_edited(&self) -> bool {
        self.removed_count > 0 || self.inserted_count() > 0
    }

    /// Whether `id` was removed (false for an id out of range).
    pub fn is_removed(&self, id: u32) -> bool {
        bit(&self.removed, id)
    }

    /// Whether `id` is an inserted triangle's.
    pub fn is_inserted(&self, id: u32) -> bool {
        id >= self.base.triangle_count() && id < self.id_count()
    }

    /// The vertices of triangle `id` relative to [`Field::origin`], or `None` if there is no such
    /// id or it was removed.
    pub fn triangle_local(&self, id: u32) -> Option<[[f32; 3]; 3]> {
        if self.is_removed(id) {
            return None;
        }
        let base = self.base.triangle_count();
        if id < base {
            return self.base.triangle_local(id);
        }
        Some(self.overlay.as_ref()?.sections().triangles.get((id - base) as usize)?.v)
    }

    /// The box of the live triangles relative to [`Field::origin`]: the field's box (removals do
    /// not shrink it) joined with the inserted triangles'.
    pub fn bounds_local(&self) -> ([f64; 3], [f64; 3]) {
        let s = self.base.reader().scene;
        let (mut lo, mut hi) = (s.aabb_min, s.aabb_max);
        if self.base.triangle_count() as u64 == self.removed_base {
            (lo, hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        }
        if let Some(o) = &self.overlay {
            let (a, b) = o.bounds();
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        (lo, hi)
    }

    fn mark(&mut self, id: u32) -> bool {
        let word = id as usize >> 6;
        if self.removed.len() <= word {
            self.removed.resize(word + 1, 0);
        }
        let was = self.removed[word] >> (id & 63) & 1 != 0;
        self.removed[word] |= 1 << (id & 63);
        if !was {
            self.removed_count += 1;
            self.removed_base += u64::from(id < self.base.triangle_count());
        }
        !was
    }

    /// Removes the triangles `ids` (the field's or inserted ones). Ids already removed are
    /// skipped. Returns how many were removed now.
    ///
    /// # Errors
    /// [`EditError::NoSuchTriangle`] for an id out of range, before anything is removed.
    pub fn remove(&mut self, ids: &[u32]) -> Result<u64, EditError> {
        let count = self.id_count();
        if let Some(&id) = ids.iter().find(|&&id| id >= count) {
            return Err(EditError::NoSuchTriangle { id, count });
        }
        let base = self.base.triangle_count();
        let mut now = 0;
        let mut inserted = Vec::new();
        for &id in ids {
            if self.mark(id) {
                now += 1;
                if id >= base {
                    inserted.push(id - base);
                }
            }
        }
        if !inserted.is_empty() {
            let overlay = self.overlay.take().expect("inserted ids have an overlay");
            let removed = &self.removed;
            let dead = move |k: u32| bit(removed, base + k);
            match overlay.remove(&inserted, &dead) {
                Ok(o) => self.overlay = Some(o),
                Err((o, TooLarge)) => {
                    // Unreachable in practice (removing shrinks blocks), but keep the promise.
                    self.overlay = Some(o);
                    for &k in &inserted {
                        self.removed[(base + k) as usize >> 6] &= !(1 << ((base + k) & 63));
                    }
                    self.removed_count -= inserted.len() as u64;
                    return Err(EditError::TooLarge);
                }
            }
        }
        Ok(now)
    }

    /// The field's triangles (not inserted ones) that come from `object`.
    pub fn ids_of(&self, object: Object<'_>) -> Vec<u32> {
        let r = self.base.reader();
        let sources: Vec<bool> = r
            .sources
            .iter()
            .map(|s| match object {
                Object::Name(name) => r.string(s.name_offset, s.name_length) == Some(name),
                Object::Mesh(m) => s.mesh == m,
                Object::Node(n) => s.node != NO_INDEX && s.node == n,
            })
            .collect();
        r.provenance
            .iter()
            .enumerate()
            .filter(|(_, p)| sources.get(p.source as usize).copied().unwrap_or(false))
            .map(|(i, _)| i as u32)
            .collect()
    }

    /// Removes every triangle of the field that comes from `object` (an OBJ object or group, a
    /// glTF mesh or node; [`Object`]). Returns how many were removed now.
    ///
    /// # Errors
    /// [`EditError::NoMatch`] if no triangle of the field comes from it, naming the objects the
    /// field has.
    pub fn remove_object(&mut self, object: Object<'_>) -> Result<u64, EditError> {
        let ids = self.ids_of(object);
        if ids.is_empty() {
            return Err(EditError::NoMatch { what: object.to_string(), known: self.object_names(8) });
        }
        self.remove(&ids)
    }

    /// Up to `most` of the field's distinct object names, quoted, for messages.
    pub fn object_names(&self, most: usize) -> String {
        let r = self.base.reader();
        let mut names: Vec<&str> = r.sources.iter().filter_map(|s| r.string(s.name_offset, s.name_length)).collect();
        names.sort_unstable();
        names.dedup();
        let shown: Vec<String> = names.iter().take(most).map(|n| format!("{n:?}")).collect();
        match names.len() {
            0 => "none".into(),
            n if n > most => format!("{}, and {} more", shown.join(", "), n - most),
            _ => shown.join(", "),
        }
    }

    /// Inserts `triangles` (in the field's own coordinates, before any instance transform),
    /// each placed by `transform`, rasterised into the field's directions, tiles and leaves in
    /// memory. Returns the ids they got: the next ones after every id in use, in order.
    /// Degenerate triangles are kept (a ray never hits them). `O(l)` per triangle for `l`
    /// directions, like a bake, on every core.
    ///
    /// # Errors
    /// [`EditError::NotFinite`], [`EditError::OutsideSphere`] (naming the first offending
    /// triangle), [`EditError::TooManyTriangles`], [`EditError::TooLarge`]; nothing is inserted.
    pub fn insert(&mut self, triangles: &[[[f64; 3]; 3]], transform: &Affine) -> Result<Range<u32>, EditError> {
        let mut ranges = self.insert_all(&[(triangles, transform)]).map_err(|(_, e)| e)?;
        Ok(ranges.remove(0))
    }

    /// [`EditedField::insert`] of several meshes, each placed by its own transform, in one pass
    /// over the field's tiles: inserting `k` meshes one call at a time rebuilds the tiles they
    /// share `k` times (a scene file of thousands of inserts took minutes), this once. Returns
    /// each mesh's ids, in order.
    ///
    /// # Errors
    /// As [`EditedField::insert`], with the index of the mesh at fault; nothing is inserted.
    pub fn insert_all(&mut self, parts: &[(&[[[f64; 3]; 3]], &Affine)]) -> Result<Vec<Range<u32>>, (usize, EditError)> {
        let total: u64 = parts.iter().map(|(t, _)| t.len() as u64).sum();
        if self.id_count() as u64 + total > u32::MAX as u64 {
            return Err((parts.len().saturating_sub(1), EditError::TooManyTriangles));
        }
        let (c, radius) = self.base.bounding_sphere();
        let mut stored = Vec::with_capacity(total as usize);
        for (part, (triangles, transform)) in parts.iter().enumerate() {
            for (k, t) in triangles.iter().enumerate() {
                let v: [[f32; 3]; 3] = t.map(|p| {
                    let w = transform.point(p);
                    std::array::from_fn(|i| (w[i] - c[i]) as f32)
                });
                if v.iter().flatten().any(|x| !x.is_finite()) {
                    return Err((part, EditError::NotFinite { triangle: k }));
                }
                let distance = v
                    .iter()
                    .map(|p| p.iter().map(|&x| (x as f64) * (x as f64)).sum::<f64>().sqrt())
                    .fold(0.0, f64::max);
                if !(distance <= radius) {
                    return Err((part, EditError::OutsideSphere { triangle: k, distance, radius }));
                }
                stored.push(TriangleRecord { v });
            }
        }
        let mut next = self.id_count();
        if !stored.is_empty() {
            let base = self.base.triangle_count();
            let overlay = self.overlay.take().unwrap_or_else(|| Overlay::empty(self.base.clone()));
            let removed = &self.removed;
            let dead = move |k: u32| bit(removed, base + k);
            match overlay.insert(&stored, &dead) {
                Ok((o, local)) => {
                    self.overlay = Some(o);
                    next = base + local.start;
                }
                Err((o, TooLarge)) => {
                    self.overlay = Some(o);
                    return Err((parts.len().saturating_sub(1), EditError::TooLarge));
                }
            }
        }
        Ok(parts
            .iter()
            .map(|(t, _)| {
                let r = next..next + t.len() as u32;
                next = r.end;
                r
            })
            .collect())
    }

    /// The closest hit of a ray given relative to [`Field::origin`], over the live triangles:
    /// the mapped field's (removed ones skipped) and the inserted ones. `prim` is the id.
    pub fn closest_hit_local(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        let view = self.base.view();
        let kept = Kept { tris: self.base.reader().triangles, removed: &self.removed };
        let mut best = Closest::new(ray.tmax);
        if let Some(h) = view.closest_hit_local_in(ray, &kept, counter) {
            best = Closest { hit: Some(h), tmax: h.t };
        }
        if let Some(o) = self.live_overlay() {
            let shorter = Ray { tmax: best.tmax, ..*ray };
            let tris = Kept { tris: &o.sections().triangles, removed: &[] };
            // An inserted triangle's id is above every mapped one, so at the same `t` the mapped
            // hit stays (`Closest::take`: the smaller id wins a tie).
            if let Some(h) = o.view().closest_hit_local_in(&shorter, &tris, counter)
                && best.hit.is_none_or(|b| h.t < b.t)
            {
                best.hit = Some(Hit { prim: h.prim + self.base.triangle_count(), ..h });
            }
        }
        best.hit
    }

    /// The first hit found on `[tmin, tmax]` of a ray given relative to [`Field::origin`].
    pub fn any_hit_local(&self, ray: &Ray, counter: &mut impl Counter) -> Option<Hit> {
        let kept = Kept { tris: self.base.reader().triangles, removed: &self.removed };
        if let Some(h) = self.base.view().any_hit_local_in(ray, &kept, counter) {
            return Some(h);
        }
        let o = self.live_overlay()?;
        let tris = Kept { tris: &o.sections().triangles, removed: &[] };
        let h = o.view().any_hit_local_in(ray, &tris, counter)?;
        Some(Hit { prim: h.prim + self.base.triangle_count(), ..h })
    }

    fn live_overlay(&self) -> Option<&Overlay> {
        self.overlay.as_ref().filter(|o| o.sections().live() > 0)
    }
}
