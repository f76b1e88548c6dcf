//! The C types of the API: status codes, constants and the records that cross the boundary,
//! laid out for C (`include/vlf.h` is generated from them).

use bytemuck::{Pod, Zeroable};
use std::ffi::c_char;
use std::mem::{align_of, offset_of, size_of};
use vlf_runtime::{Field, Hit, Ray};

/// What a call did: `VLF_OK` (0) on success, otherwise why it failed. The values are stable.
#[allow(non_camel_case_types)]
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VlfStatus {
    /// Success.
    VLF_OK = 0,
    /// A required pointer argument was null.
    VLF_ERR_NULL_ARGUMENT = 1,
    /// An argument was out of range, misaligned, or overlapped another (the message says which).
    VLF_ERR_INVALID_ARGUMENT = 2,
    /// The operating system refused to open, read or map the file.
    VLF_ERR_IO = 3,
    /// The bytes are not a valid field: wrong magic, unsupported version, corrupt header or
    /// section table, or (for provenance) a corrupt reference inside a section.
    VLF_ERR_FORMAT = 4,
    /// A bug in this library (a caught Rust panic). Please report it with the message.
    VLF_ERR_INTERNAL = 5,
    /// Memory for the field could not be allocated (opening from memory, or decoding a packed
    /// field).
    VLF_ERR_OUT_OF_MEMORY = 6,
}

/// The triangle id of a miss (`0xFFFFFFFF`), as in a hits file.
pub const VLF_NO_PRIM: u32 = u32::MAX;

/// The value of an absent index in `VlfProvenance` (`node` outside glTF, `material` when there
/// is none).
pub const VLF_NO_INDEX: u32 = u32::MAX;

/// `VlfProvenance.kind`: the triangle came from an OBJ object or group.
pub const VLF_SOURCE_OBJ: u32 = 1;
/// `VlfProvenance.kind`: the triangle came from a glTF mesh primitive.
pub const VLF_SOURCE_GLTF: u32 = 2;
/// `VlfProvenance.kind`: the triangle was supplied by a program.
pub const VLF_SOURCE_PROGRAM: u32 = 3;

/// A ray `org + t·dir` for `t` in `[tmin, tmax]`. `dir` need not be unit length; `t` is measured
/// in units of `dir`. 32 bytes, laid out exactly as a record of a rays file (`formats/rays.md`),
/// so a rays file read into memory is an array of `VlfRay`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct VlfRay {
    /// Origin.
    pub org: [f32; 3],
    /// Start of the interval (usually 0).
    pub tmin: f32,
    /// Direction; any nonzero length.
    pub dir: [f32; 3],
    /// End of the interval (`INFINITY` for an unbounded ray).
    pub tmax: f32,
}

/// A hit record: 16 bytes, laid out exactly as a record of a hits file (`formats/rays.md`).
/// On a miss: `t = +inf`, `prim = VLF_NO_PRIM`, `u = v = 0`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct VlfHit {
    /// The ray parameter of the hit: the hit point is `org + t·dir`.
    pub t: f32,
    /// The triangle id, an index into the field's triangles (`vlf_triangle`, `vlf_provenance`).
    pub prim: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex: the hit point is
    /// `(1 − u − v)·v0 + u·v1 + v·v2`.
    pub v: f32,
}

// The C structs are the runtime's, field for field, so arrays pass without a copy.
const _: () = {
    assert!(size_of::<VlfRay>() == 32 && size_of::<Ray>() == 32);
    assert!(align_of::<VlfRay>() == align_of::<Ray>());
    assert!(offset_of!(VlfRay, org) == offset_of!(Ray, org));
    assert!(offset_of!(VlfRay, tmin) == offset_of!(Ray, tmin));
    assert!(offset_of!(VlfRay, dir) == offset_of!(Ray, dir));
    assert!(offset_of!(VlfRay, tmax) == offset_of!(Ray, tmax));
    assert!(size_of::<VlfHit>() == 16 && size_of::<Hit>() == 16);
    assert!(align_of::<VlfHit>() == align_of::<Hit>());
    assert!(offset_of!(VlfHit, t) == offset_of!(Hit, t));
    assert!(offset_of!(VlfHit, prim) == offset_of!(Hit, prim));
    assert!(offset_of!(VlfHit, u) == offset_of!(Hit, u));
    assert!(offset_of!(VlfHit, v) == offset_of!(Hit, v));
};

/// Where a triangle came from: its input file, the object or mesh within it, and its index there.
///
/// `input` and `name` point into the open field and are **not** NUL-terminated: use them with
/// their lengths (`printf("%.*s", (int)p.input_len, p.input)`). They are valid UTF-8 and stay
/// valid until the field is closed.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VlfProvenance {
    /// The input file's name (its final path component), `input_len` bytes.
    pub input: *const c_char,
    /// Length of `input` in bytes.
    pub input_len: usize,
    /// The OBJ object or group name, or the glTF mesh name; may be empty.
    pub name: *const c_char,
    /// Length of `name` in bytes.
    pub name_len: usize,
    /// `VLF_SOURCE_OBJ`, `VLF_SOURCE_GLTF` or `VLF_SOURCE_PROGRAM`.
    pub kind: u32,
    /// The OBJ model index or the glTF mesh index.
    pub mesh: u32,
    /// The glTF primitive index within the mesh (0 otherwise).
    pub primitive: u32,
    /// The glTF node index (`VLF_NO_INDEX` otherwise).
    pub node: u32,
    /// The material index in the input (`VLF_NO_INDEX` if none).
    pub material: u32,
    /// The triangle's index within its source.
    pub index: u32,
}

/// An open field. Opaque: create it with `vlf_open_path` or `vlf_open_memory`, release it with
/// `vlf_close`. Immutable, so it may be queried from many threads at once.
pub struct VlfField {
    pub(crate) field: Field,
}
