//! Dynamic scenes over baked visibility fields: what moves at run time, on top of fields that do
//! not.
//!
//! - **Instances** ([`Scene`]): fields placed in the world by affine transforms (rotation,
//!   non-uniform scale, mirroring, translation), each with an id and a 32-bit mask that rays
//!   filter on. A field is mapped once and shared by all its instances. A top-level hierarchy
//!   over the instances' world boxes is built in `O(n log n)` for `n` instances and refitted in
//!   `O(depth)` when one moves: moving an instance costs nothing proportional to its triangles.
//!   A ray is transformed into each candidate instance's field and answered there; `t` stays in
//!   the world ray's units; hits name the instance and the triangle.
//! - **Edits** ([`EditedField`]), the paper's §7: triangles removed from a mapped field (by id,
//!   or by provenance: an OBJ object or group, a glTF mesh or node) and triangles inserted
//!   (a mesh with a transform), rasterised into the field's own directions, tiles and leaves in
//!   memory by the bake's kernel (`vlf-raster`) and queried together with the untouched mapped
//!   bytes. Edits never write the file; saving an edited field is a new bake.
//! - **The scene file** ([`SceneFile`], `formats/scene.md`): JSON placing fields and editing them.
//!
//! ```no_run
//! use std::sync::Arc;
//! use vlf_runtime::{Field, Ray};
//! use vlf_scene::{Affine, EditedField, Object, Scene};
//!
//! let prop = Arc::new(Field::open("chair.vlf")?);
//! let mut scene = Scene::new();
//! let chair = scene.add_field(EditedField::new(prop));
//! let a = scene.add_instance(chair, Affine::IDENTITY, 0xFFFF_FFFF)?;
//! let b = scene.add_instance(chair, Affine::translation([2.0, 0.0, 0.0]), 0b10)?;
//! scene.set_transform(b, Affine::translation([3.0, 0.0, 1.0]))?; // O(depth), not O(triangles)
//! scene.edit(chair, |f| f.remove_object(Object::Name("Cushion"))); // both instances lose it
//! if let Some(h) = scene.closest_hit(&Ray::new([0.0, 0.5, 5.0], [0.0, 0.0, -1.0]), 0xFFFF_FFFF) {
//!     println!("instance {} triangle {} at t = {}", h.instance, h.hit.prim, h.hit.t);
//! }
//! # let _ = a;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Queries take `&self` and allocate nothing; a [`Scene`] is `Send + Sync`. Changes take
//! `&mut self`.

#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod affine;
mod bvh;
pub mod edit;
pub mod file;
mod overlay;
pub mod scene;

pub use affine::{Affine, AffineError};
pub use edit::{EditError, EditedField, Object};
pub use file::{InsertSpec, InstanceSpec, MeshLoader, SceneFile, SceneFileError};
pub use scene::{FieldId, Flat, InstanceId, InstanceInfo, Scene, SceneError, SceneHit};
