//! Load a baked VLF visibility field instantly and answer ray queries from the mapped bytes.
//!
//! A field is the data structure of Mortensen et al., *A Visibility Field for Ray Tracing*:
//! for each of `l` directions an `n × n` grid of parallel beams, each with a 1D BSP of the
//! triangles along it. `vlf-bake` writes it (`formats/vlf.md` is the byte-level contract);
//! [`Field::open`] maps the file and checks its header and section table in time independent of
//! the file's size; queries then read the mapped bytes directly, so the first ray is answered
//! as soon as the pages it touches are read.
//!
//! ```
//! use vlf_runtime::{Field, Ray};
//!
//! # let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/fields/tiny.vlf");
//! // A unit box centred on the origin (fixtures/fields/tiny.vlf: 12 triangles, 10 KB).
//! let field = Field::open(path)?; // maps the file and checks its header: O(1) in its size
//! let ray = Ray::new([0.1, 0.2, 2.0], [0.0, 0.0, -1.0]);
//!
//! let hit = field.closest_hit(&ray).expect("the ray hits the box");
//! assert_eq!(hit.t, 1.5); // the face at z = 0.5; the hit point is ray.at(t)
//! let origin = field.provenance(hit.prim).expect("every triangle has a provenance");
//! assert_eq!(origin.input, "Box.gltf");
//! println!("t = {}: triangle {} of mesh {} in {}", hit.t, origin.index, origin.mesh, origin.input);
//!
//! assert!(field.any_hit(&ray)); // a shadow ray: stops at the first hit found
//! assert!(!field.any_hit(&Ray::new([0.1, 0.2, 2.0], [0.0, 0.0, 1.0]))); // pointing away
//! # Ok::<(), vlf_runtime::OpenError>(())
//! ```
//!
//! # Guarantees
//! - **Opening a raw field is O(1)** in the file's size: [`Field::open`] maps the file and checks
//!   the header, the section table and the content hash over those two (`formats/vlf.md` §7).
//!   Nothing else is read until a query touches it. (A packed field is decoded at open: below.)
//! - **Queries never panic and never read out of bounds**, whatever the file says: a file that
//!   passed the open checks but lies inside a section gives wrong answers for the rays that touch
//!   the lie, and nothing worse. `vlf-bake dump --verify` checks every byte.
//! - **The answers are exact** with respect to the watertight triangle test
//!   ([`vlf_geom::TriRay`]): the same `t`, bit for bit, as testing every triangle.
//! - **Queries allocate nothing** and take `&self`: [`Field`] is `Send + Sync`; share one across
//!   threads. With the `rayon` feature, `par_closest_hits` and `par_any_hits` trace batches on
//!   all cores.
//! - **Every hit along a ray** ([`FieldView::all_hits`], each triangle once, in order of `t`, with
//!   a per-ray maximum) and **hit counts** ([`FieldView::hit_count`]), on `field.view()`, walk the
//!   same leaves with the same kernel: the same hits, bit for bit, as testing every triangle. They
//!   allocate only the list they return (or grow the one [`FieldView::all_hits_into`] is given).
//! - **Invalid rays miss**: a ray with a non-finite or zero direction, a non-finite origin, a NaN
//!   bound or `tmin > tmax` has no hit (see [`Ray::is_valid`]).
//!
//! A field of format 1.1 may also carry what a renderer needs besides geometry: each triangle's
//! [`Material`] (through its provenance), and the [`SceneCamera`]s and [`SceneLight`]s of a glTF
//! input. A field without them (every 1.0 field) returns `None` and empty iterators, and the
//! renderer supplies its own defaults.
//!
//! **Packed fields** (`vlf-bake pack`, `formats/vlf.md` §8) open through the same calls, but not
//! instantly: their zstd sections are decoded into one owned, 64-byte-aligned buffer laid out as
//! the raw field, which costs time and memory linear in the field's size (see
//! [`Field::is_packed`], [`OpenOptions::max_unpacked_bytes`]). Raw fields stay zero-copy. Decoding
//! needs the `packed` cargo feature (on by default; it links the zstd C library); without it a
//! packed field is refused with an error that says so.
//!
//! The C API over this crate is `crates/vlf-capi` (`docs/c-api.md`).

#![deny(missing_docs)]

mod all_hits;
mod batch;
mod filter;
pub mod memory;
mod open_error;
mod prefetch;
mod query;
pub mod regular;
mod scene;
mod setup;
#[cfg(test)]
mod test_rng;
mod trace;
mod walk;

use std::io::Read;
use std::path::Path;
use vlf_format::pack::Unpacked;
use vlf_format::{AlignedBytes, NO_INDEX};

pub use all_hits::{HitLists, TooManyHits};
pub use batch::Interleave;
pub use open_error::OpenError;
use open_error::mappable;

/// Rays per work item of the parallel batch queries.
#[cfg(feature = "rayon")]
const PAR_CHUNK: usize = 1024;
pub use query::{FieldView, InstructionSet};
use scene::SceneSections;
pub use scene::{CameraProjection, LightKind, Material, SceneCamera, SceneLight};
pub use vlf_format::pack::PackedLayout;
pub use vlf_format::{FieldReader, FormatError, hex};
pub use vlf_geom::{Counter, Hit, Intersector, Ray, TraceStats};

/// Where a field's bytes live.
enum Backing {
    /// A read-only memory map of the file.
    Map(memmap2::Mmap),
    /// An owned buffer, 64-byte aligned so sections can be cast in place: a copy of raw bytes, or
    /// a packed field decoded.
    Owned(AlignedBytes),
}

impl Backing {
    fn bytes(&self) -> &[u8] {
        match self {
            Backing::Map(m) => m,
            Backing::Owned(b) => b.as_bytes(),
        }
    }
}

self_cell::self_cell!(
    struct FieldCell {
        owner: Backing,
        #[covariant]
        dependent: FieldView,
    }
);

/// An open visibility field: the mapped (or owned) bytes and the query engine over them.
///
/// Immutable once open: every method takes `&self`, and a `Field` is `Send + Sync`, so one field
/// serves any number of threads. Dropping it unmaps the file.
pub struct Field {
    cell: FieldCell,
    /// How a packed field was stored; `None` for a raw one.
    packed: Option<Box<PackedLayout>>,
}

/// How to open a field. [`Field::open`], [`Field::read`] and [`Field::from_bytes`] use the
/// defaults.
///
/// ```no_run
/// use vlf_runtime::OpenOptions;
///
/// // Refuse packed fields that would take more than 1 GiB of memory once decoded.
/// let field = OpenOptions::new().max_unpacked_bytes(1 << 30).open("scene.vlf")?;
/// # Ok::<(), vlf_runtime::OpenError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct OpenOptions {
    #[cfg_attr(not(feature = "packed"), allow(dead_code))]
    max_unpacked_bytes: Option<u64>,
}

/// Where a triangle came from (the field's PROVENANCE, SOURCES and INPUTS sections).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Provenance<'a> {
    /// The input file's name (final path component).
    pub input: &'a str,
    /// The object or group (OBJ) or mesh (glTF) name; may be empty.
    pub name: &'a str,
    /// 1 = OBJ object or group, 2 = glTF primitive, 3 = supplied by a program.
    pub kind: u32,
    /// OBJ model index or glTF mesh index.
    pub mesh: u32,
    /// glTF primitive index within the mesh (0 otherwise).
    pub primitive: u32,
    /// glTF node index; `None` outside glTF.
    pub node: Option<u32>,
    /// Material index in the input; `None` if the source has no material.
    pub material: Option<u32>,
    /// The triangle's index within its source.
    pub index: u32,
}

/// The parameters of a bake (`formats/vlf.md` §5.2): what was asked for and what the baker chose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameters {
    /// The lattice size `N`: the field stores `2N² + 1` directions.
    pub lattice_n: u32,
    /// The number of stored directions.
    pub directions: u32,
    /// Tiles per side of each direction's grid.
    pub tiles: u32,
    /// The leaf policy's target number of triangles per leaf.
    pub leaf_size: u32,
    /// The leaf policy's largest depth.
    pub max_depth: u32,
    /// The conservative margin `μ`, in world units.
    pub margin: f64,
    /// The directions asked for; `None` if the baker chose them.
    pub requested_directions: Option<u32>,
    /// The tiles asked for; `None` if the baker chose them.
    pub requested_tiles: Option<u32>,
    /// The size budget of automatic parameters, and the ceiling of explicit ones, in bytes.
    pub max_bytes: u64,
    /// The budget per triangle of automatic parameters, in bytes.
    pub max_bytes_per_triangle: u64,
}

impl OpenOptions {
    /// The defaults: a packed field may be decoded into no more memory than
    /// [`memory::budget`] allows when it is opened (see [`OpenOptions::max_unpacked_bytes`]).
    pub fn new() -> OpenOptions {
        OpenOptions::default()
    }

    /// Refuse a packed field whose decoded size (which its section table states, before anything
    /// is allocated) exceeds `bytes`, with [`FormatError::UnpackedTooLarge`]. Raw fields are not
    /// affected.
    ///
    /// Without this call the limit is [`memory::budget`], read when a packed field is opened:
    /// three quarters of the memory the system reports available, or what the address-space limit
    /// leaves. A few hundred kilobytes of zstd frames can claim gigabytes (up to
    /// [`vlf_format::MAX_ZSTD_EXPANSION`] times their size, the format's own bound), and a claim
    /// the system could only meet by swapping or by killing the process is refused instead.
    /// Where the system reports neither (not Linux), only the format's bound applies. To decode
    /// more, pass a larger limit (`u64::MAX`: the format's bound alone); an allocation that fails
    /// is then [`FormatError::OutOfMemory`], not an abort. `vlf-bake unpack` decodes to a file
    /// instead, in bounded memory.
    pub fn max_unpacked_bytes(&mut self, bytes: u64) -> &mut OpenOptions {
        self.max_unpacked_bytes = Some(bytes);
        self
    }

    /// The limit set by [`OpenOptions::max_unpacked_bytes`], if any (`None`: the default, the
    /// memory budget when each field is opened): for a caller that opens several fields and holds
    /// them to one budget together.
    pub fn unpacked_limit(&self) -> Option<u64> {
        self.max_unpacked_bytes
    }

    /// Opens a field by memory-mapping it. Checks the header, the section table and the content
    /// hash, in time independent of the file's size (no section is read or hashed: `vlf-bake dump
    /// --verify` does that); reads nothing else until queried.
    ///
    /// # Errors
    /// [`OpenError::Io`] if the file cannot be opened or mapped; [`OpenError::Format`] if its
    /// bytes are not a valid field (bad magic, unsupported major version, a header or table fault,
    /// a missing or misaligned section: [`FormatError`] has one variant per fault), or a packed
    /// field that does not decode or exceeds [`OpenOptions::max_unpacked_bytes`].
    ///
    /// A packed field (`formats/vlf.md` §8) cannot be used in place: it is decoded into memory
    /// here, every section's length and hash checked, in time and memory linear in the field's
    /// size. See [`Field::is_packed`].
    ///
    /// # The mapping contract
    /// The file must not be modified in place or truncated while the field is open: the mapping
    /// shows the file's current bytes. `vlf-bake` never does either: it writes a new file and
    /// renames it over the old one, which leaves this mapping on the old file. Should another
    /// program modify the file in place anyway, every read from the mapping is bounds-checked, so
    /// the queries give wrong answers but never read outside the mapping; a truncation makes the
    /// operating system raise `SIGBUS` on access. If you cannot rule that out, use [`Field::read`].
    pub fn open(&self, path: impl AsRef<Path>) -> Result<Field, OpenError> {
        let path = path.as_ref();
        let io = |error| OpenError::Io { path: path.to_owned(), error };
        // Only a regular file can be mapped. Checked before opening too: opening a pipe waits for
        // a writer, forever if none comes.
        let (file, meta) = regular::open_regular_file(path).map_err(mappable).map_err(io)?;
        let len = meta.len();
        if len < vlf_format::HEADER_SIZE as u64 {
            // Too short to map usefully; let the reader name the problem.
            let mut bytes = Vec::new();
            file.take(len).read_to_end(&mut bytes).map_err(io)?;
            return self.from_bytes(&bytes).map_err(|e| e.with_path(path));
        }
        // SAFETY: `Mmap::map` is unsafe because the mapped file could change underneath us. This
        // is the mapping contract documented above: our tools never modify a field in place, and
        // every read through the mapping is bounds-checked, so a concurrent modification by a
        // third party yields wrong answers rather than out-of-bounds reads. The mapping is
        // read-only and lives as long as the `Field` (it is the self_cell owner), or, for a
        // packed field, until it is decoded.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
        // Queries jump around a big field: ask for huge pages, so that fewer translations miss
        // the TLB (where the kernel and file system support them for file mappings; elsewhere
        // this is a no-op). O(1): it changes how the mapping is faulted in, not the file.
        #[cfg(target_os = "linux")]
        if std::env::var_os("VLF_NO_HUGEPAGE").is_none() {
            let _ = map.advise(memmap2::Advice::HugePage);
        }
        let field = match self.unpack_if_packed(&map) {
            Ok(Some(unpacked)) => Field::from_unpacked(unpacked),
            Ok(None) => Field::from_backing(Backing::Map(map), None),
            Err(e) => Err(e.into()),
        };
        field.map_err(|e| e.with_path(path))
    }

    /// Opens a field by reading the whole file into memory: no mapping contract (the file may
    /// change or vanish afterwards), at the price of time and memory linear in the file's size.
    ///
    /// # Errors
    /// As [`OpenOptions::open`].
    pub fn read(&self, path: impl AsRef<Path>) -> Result<Field, OpenError> {
        let path = path.as_ref();
        // Only a regular file: `/dev/zero` would be read until memory ran out, a pipe waited on.
        let bytes = regular::read_regular_file(path, u64::MAX)
            .map_err(|error| OpenError::Io { path: path.to_owned(), error })?;
        self.from_bytes(&bytes).map_err(|e| e.with_path(path))
    }

    /// Opens a field from bytes already in memory. Raw bytes are copied once into an aligned
    /// buffer (to query borrowed, aligned bytes without a copy use [`FieldView::from_bytes`]); a
    /// packed field is decoded from them. Time and memory linear in their length.
    ///
    /// # Errors
    /// [`OpenError::Bytes`] if the bytes are not a valid field.
    pub fn from_bytes(&self, bytes: &[u8]) -> Result<Field, OpenError> {
        match self.unpack_if_packed(bytes)? {
            Some(unpacked) => Field::from_unpacked(unpacked),
            None => Field::from_backing(Backing::Owned(AlignedBytes::copy_of(bytes)?), None),
        }
    }

    /// The decoded field if `bytes` are a packed field; `None` for a raw field, and for bytes
    /// whose fault the reader will name.
    #[cfg(feature = "packed")]
    fn unpack_if_packed(&self, bytes: &[u8]) -> Result<Option<Unpacked>, FormatError> {
        match vlf_format::parse_head(bytes, bytes.len() as u64) {
            Ok((_, table)) if vlf_format::pack::is_packed(&table) => {
                vlf_format::pack::unpack_in_memory(bytes, self.decode_limit()).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// The most bytes a packed field may be decoded into: the caller's limit, else the memory
    /// budget where the system reports one.
    #[cfg(feature = "packed")]
    fn decode_limit(&self) -> Option<u64> {
        self.max_unpacked_bytes.or_else(|| Some(memory::budget()).filter(|b| b.is_reported()).map(|b| b.bytes))
    }

    /// Without the `packed` feature nothing is decoded: the reader refuses a compressed section
    /// with [`FormatError::CompressedSection`], whose message names the feature.
    #[cfg(not(feature = "packed"))]
    fn unpack_if_packed(&self, _bytes: &[u8]) -> Result<Option<Unpacked>, FormatError> {
        Ok(None)
    }
}

impl Field {
    /// Opens a field by memory-mapping it: [`OpenOptions::open`] with the default options, whose
    /// documentation states the mapping contract. Checks the header and section table (time
    /// independent of the file size); reads nothing else until queried. A packed field is decoded
    /// into memory instead (not instant; see [`Field::is_packed`]).
    pub fn open(path: impl AsRef<Path>) -> Result<Field, OpenError> {
        OpenOptions::new().open(path)
    }

    /// Opens a field by reading the whole file into memory (no mapping contract; time linear in
    /// the file size): [`OpenOptions::read`] with the default options.
    pub fn read(path: impl AsRef<Path>) -> Result<Field, OpenError> {
        OpenOptions::new().read(path)
    }

    /// Opens a field from bytes already in memory: [`OpenOptions::from_bytes`] with the default
    /// options. The bytes are copied once into an aligned buffer (a packed field is decoded from
    /// them); to query borrowed, aligned bytes without a copy use [`FieldView::from_bytes`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Field, OpenError> {
        OpenOptions::new().from_bytes(bytes)
    }

    fn from_backing(backing: Backing, packed: Option<Box<PackedLayout>>) -> Result<Field, OpenError> {
        let cell = FieldCell::try_new(backing, |b| FieldReader::new(b.bytes()).map(FieldView::new))?;
        Ok(Field { cell, packed })
    }

    fn from_unpacked(unpacked: Unpacked) -> Result<Field, OpenError> {
        Field::from_backing(Backing::Owned(unpacked.bytes), Some(Box::new(unpacked.packed)))
    }

    /// Whether the field was stored packed (zstd sections, `formats/vlf.md` §8) and was decoded
    /// into memory when opened. Its bytes, [`Field::content_hash`] and answers are those of the
    /// raw field `vlf-bake unpack` would write; opening it took time and memory linear in its size.
    pub fn is_packed(&self) -> bool {
        self.packed.is_some()
    }

    /// How a packed field was stored: its header and section table as in the file (codecs,
    /// stored lengths, the packed file's own content hash). `None` for a raw field.
    pub fn packed_layout(&self) -> Option<&PackedLayout> {
        self.packed.as_deref()
    }

    /// The query engine over the field's bytes: the same queries as `Field`'s, plus the counted
    /// variants and the candidate walk that tools and benchmarks use.
    #[inline(always)]
    pub fn view(&self) -> &FieldView<'_> {
        self.cell.borrow_dependent()
    }

    /// The validated sections as typed slices of the field, for tools. Values inside the sections
    /// have not been checked (see [`FieldReader`]).
    pub fn reader(&self) -> &FieldReader<'_> {
        &self.view().reader
    }

    /// The closest hit of `ray` on `[tmin, tmax]`, or `None` on a miss or an invalid ray.
    ///
    /// The same hit, bit for bit, as testing every triangle with the watertight kernel. Cost: a
    /// constant-time direction lookup, then the tiles the ray crosses (at most about
    /// `1 + √2 · n · sin α` for tile resolution `n` and angle `α` to the chosen direction), and in
    /// each the BSP leaves its segment passes, front to back, stopping as soon as the best hit
    /// lies within the part of the ray already searched. Allocates nothing.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.view().closest_hit(ray)
    }

    /// Whether `ray` hits anything on `[tmin, tmax]` (a shadow ray); `false` for an invalid ray.
    /// The walk of [`Field::closest_hit`], stopping at the first hit found, and ordered so as to
    /// search the surface a shadow ray leaves last: a segment that leaves the scene (towards a
    /// light outside it) is walked from that far end, any other from its origin with the leaf it
    /// starts in searched last. Allocates nothing.
    #[inline]
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.view().any_hit(ray)
    }

    /// [`Field::closest_hit`] for a ray whose origin is given relative to [`Field::origin`]: the
    /// same answer for the same ray, with the precision of the scene's own size however far the
    /// scene is from the world's origin.
    #[inline]
    pub fn closest_hit_local(&self, ray: &Ray) -> Option<Hit> {
        self.view().closest_hit_local(ray)
    }

    /// [`Field::any_hit`] for a ray given relative to [`Field::origin`].
    #[inline]
    pub fn any_hit_local(&self, ray: &Ray) -> bool {
        self.view().any_hit_local(ray)
    }

    /// Closest hits of a batch on the calling thread: `out[i]` is the hit record of `rays[i]`
    /// ([`Hit::MISS`] on a miss), the same as [`Field::closest_hit`] gives, bit for bit.
    /// Rays whose neighbours start far from them are traced several at a time, interleaved so
    /// that their cache misses overlap ([`FieldView::closest_hits`]). Allocates nothing.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn closest_hits(&self, rays: &[Ray], out: &mut [Hit]) {
        assert_eq!(rays.len(), out.len(), "one output per ray");
        self.view().closest_hits_each(rays, Interleave::Auto, |i, hit| out[i] = Hit::record(hit));
    }

    /// Any-hit answers of a batch on the calling thread: `out[i]` is [`Field::any_hit`] of
    /// `rays[i]`. Interleaved as [`Field::closest_hits`]. Allocates nothing.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        self.view().any_hits(rays, out);
    }

    /// [`Field::closest_hits`] on all cores (rayon's global pool, or the pool installed around
    /// the call). Same answers, in the same order.
    ///
    /// # Panics
    /// If the slices differ in length.
    #[cfg(feature = "rayon")]
    pub fn par_closest_hits(&self, rays: &[Ray], out: &mut [Hit]) {
        use rayon::prelude::*;
        assert_eq!(rays.len(), out.len(), "one output per ray");
        rays.par_chunks(PAR_CHUNK).zip(out.par_chunks_mut(PAR_CHUNK)).for_each(|(r, o)| self.closest_hits(r, o));
    }

    /// [`Field::any_hits`] on all cores. Same answers, in the same order.
    ///
    /// # Panics
    /// If the slices differ in length.
    #[cfg(feature = "rayon")]
    pub fn par_any_hits(&self, rays: &[Ray], out: &mut [bool]) {
        use rayon::prelude::*;
        assert_eq!(rays.len(), out.len(), "one output per ray");
        rays.par_chunks(PAR_CHUNK).zip(out.par_chunks_mut(PAR_CHUNK)).for_each(|(r, o)| self.any_hits(r, o));
    }

    /// Where triangle `id` came from: input file, object or mesh, index within it. `None` if
    /// `id` is not below [`Field::triangle_count`], or if the file's provenance of that triangle
    /// is corrupt (a reference out of bounds or a name that is not UTF-8). O(1).
    pub fn provenance(&self, id: u32) -> Option<Provenance<'_>> {
        let p = self.reader().provenance.get(id as usize)?;
        self.source_provenance(p.source, p.index)
    }

    /// Where the triangles merged into triangle `id` came from: input triangles with exactly its
    /// vertices (`formats/vlf.md` §5.13), which a ray cannot tell apart from it. Empty for most
    /// triangles; [`Field::provenance`] gives the kept one's.
    pub fn duplicates(&self, id: u32) -> impl Iterator<Item = Provenance<'_>> + '_ {
        let d = self.reader().duplicates;
        let first = d.partition_point(|r| r.triangle < id);
        d[first..]
            .iter()
            .take_while(move |r| r.triangle == id)
            .filter_map(|r| self.source_provenance(r.source, r.index))
    }

    /// The provenance of triangle number `index` of source `source`, if the file's references are
    /// sound.
    fn source_provenance(&self, source: u32, index: u32) -> Option<Provenance<'_>> {
        let r = self.reader();
        let s = r.sources.get(source as usize)?;
        let input = r.inputs.get(s.input as usize)?;
        Some(Provenance {
            input: r.string(input.name_offset, input.name_length)?,
            name: r.string(s.name_offset, s.name_length)?,
            kind: s.kind,
            mesh: s.mesh,
            primitive: s.primitive,
            node: (s.node != NO_INDEX).then_some(s.node),
            material: (s.material != NO_INDEX).then_some(s.material),
            index,
        })
    }

    /// The vertices of triangle `id` in world coordinates (its stored vertices plus
    /// [`Field::origin`], in f64), or `None` if `id` is not below [`Field::triangle_count`]. A
    /// hit's point is `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub fn triangle(&self, id: u32) -> Option<[[f64; 3]; 3]> {
        let c = self.origin();
        let t = self.triangle_local(id)?;
        Some(t.map(|v| std::array::from_fn(|i| v[i] as f64 + c[i])))
    }

    /// The vertices of triangle `id` as stored: relative to [`Field::origin`], in f32.
    pub fn triangle_local(&self, id: u32) -> Option<[[f32; 3]; 3]> {
        Some(self.reader().triangles.get(id as usize)?.v)
    }

    /// The point the field's triangles are stored relative to: the centre of the scene, in world
    /// coordinates (`formats/vlf.md` §5.7). Rays near a scene far from the world's origin are best
    /// given relative to it ([`Field::closest_hit_local`]): an f32 ray origin at 10⁷ is only
    /// precise to about a unit.
    pub fn origin(&self) -> [f64; 3] {
        self.reader().scene.center
    }

    /// The content hash (`formats/vlf.md` §3.1), which identifies these exact bytes. For a packed
    /// field, that of the raw field it decodes to; the packed file's own is in
    /// [`Field::packed_layout`].
    pub fn content_hash(&self) -> [u8; 32] {
        self.reader().header.content_hash
    }

    /// The input hash (§3.2), which identifies the bake's inputs and parameters.
    pub fn input_hash(&self) -> [u8; 32] {
        self.reader().header.input_hash
    }

    /// The number of triangles; triangle ids run from 0 to `triangle_count() − 1`.
    pub fn triangle_count(&self) -> u32 {
        self.reader().triangles.len() as u32
    }

    /// The number of stored directions `l` (a lattice size `2N² + 1`).
    pub fn direction_count(&self) -> u32 {
        self.reader().params.direction_count
    }

    /// Tiles per side `n` of each direction's `n × n` beam grid.
    pub fn tile_resolution(&self) -> u32 {
        self.reader().params.tile_resolution
    }

    /// Centre and radius of the scene's bounding sphere; every triangle lies inside it, and a ray
    /// that misses it misses everything.
    pub fn bounding_sphere(&self) -> ([f64; 3], f64) {
        (self.reader().scene.center, self.reader().scene.radius)
    }

    /// The corners of the box around every vertex, in world coordinates: the scene's extent,
    /// tighter than [`Field::bounding_sphere`].
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let (s, c) = (self.reader().scene, self.origin());
        (std::array::from_fn(|i| s.aabb_min[i] + c[i]), std::array::from_fn(|i| s.aabb_max[i] + c[i]))
    }

    /// The format version of the file, `(major, minor)` (`formats/vlf.md` §3.4).
    pub fn format_version(&self) -> (u16, u16) {
        let h = self.reader().header;
        (h.version_major, h.version_minor)
    }

    /// The parameters the field was baked with, as asked for and as chosen.
    pub fn parameters(&self) -> Parameters {
        let p = self.reader().params;
        Parameters {
            lattice_n: p.lattice_n,
            directions: p.direction_count,
            tiles: p.tile_resolution,
            leaf_size: p.leaf_size,
            max_depth: p.max_depth,
            margin: p.margin,
            requested_directions: p.requested_directions(),
            requested_tiles: p.requested_tiles(),
            max_bytes: p.max_bytes,
            max_bytes_per_triangle: p.max_bytes_per_triangle,
        }
    }

    /// The size of the field in bytes (for a packed field, decoded).
    pub fn len_bytes(&self) -> u64 {
        self.reader().bytes.len() as u64
    }
}

impl<'a> FieldView<'a> {
    /// A query engine over borrowed bytes of a raw field, without a copy: the checks of
    /// [`Field::open`], in time independent of the length.
    ///
    /// # Errors
    /// [`FormatError::Misaligned`] if the bytes are not 8-byte aligned (a memory map or a
    /// `Vec<u64>`-backed buffer is); [`FormatError::CompressedSection`] for a packed field (open
    /// it with [`Field::from_bytes`], which decodes it); any other [`FormatError`] if they are not
    /// a valid field.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<FieldView<'a>, FormatError> {
        FieldReader::new(bytes).map(FieldView::new)
    }

    /// A query engine over sections a caller assembled: `FieldReader`'s fields may borrow from
    /// different places, say a mapped field's directions, rotations and lookup with tiles,
    /// leaves and triangles built in memory (`vlf-scene` inserts triangles into a field this
    /// way). The queries read only the sections, bounds-checked as always: sections that do not
    /// agree with each other give wrong answers, never a panic or an out-of-bounds read.
    pub fn from_reader(reader: FieldReader<'a>) -> FieldView<'a> {
        FieldView::new(reader)
    }
}

impl Field {
    /// Every material the field holds, in MATERIALS order (sorted by input, then index).
    pub fn materials(&self) -> impl ExactSizeIterator<Item = Material<'_>> + '_ {
        SceneSections(*self.reader()).materials()
    }

    /// The position in [`Field::materials`] of the material of triangle `prim`: its source's
    /// material, looked up by (input, index) with a binary search. `None` if the triangle has no
    /// material or the field holds no record for it (a 1.0 field holds none): use a default.
    pub fn material_index(&self, prim: u32) -> Option<usize> {
        SceneSections(*self.reader()).material_index(prim)
    }

    /// The material of triangle `prim` ([`Field::material_index`]).
    pub fn material(&self, prim: u32) -> Option<Material<'_>> {
        SceneSections(*self.reader()).material(prim)
    }

    /// The cameras of the field's glTF inputs, in node order. A record of an unknown kind (a
    /// newer or damaged file) is skipped.
    pub fn cameras(&self) -> impl Iterator<Item = SceneCamera<'_>> + '_ {
        SceneSections(*self.reader()).cameras()
    }

    /// The punctual lights of the field's glTF inputs, in node order. A record of an unknown kind
    /// is skipped.
    pub fn lights(&self) -> impl Iterator<Item = SceneLight<'_>> + '_ {
        SceneSections(*self.reader()).lights()
    }
}

impl Intersector for Field {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        Field::closest_hit(self, ray)
    }
    fn any_hit(&self, ray: &Ray) -> bool {
        Field::any_hit(self, ray)
    }
    fn closest_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.view().closest_hit_counted(ray, work)
    }
    fn any_hit_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.view().any_hit_counted(ray, work)
    }
    fn origin(&self) -> [f64; 3] {
        Field::origin(self)
    }
    fn closest_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.view().closest_hit_local_counted(ray, work)
    }
    fn any_hit_local_counted(&self, ray: &Ray, work: &mut TraceStats) -> Option<Hit> {
        self.view().any_hit_local_counted(ray, work)
    }
}

#[allow(dead_code)]
fn assert_send_sync() {
    fn is<T: Send + Sync>() {}
    is::<Field>();
}
