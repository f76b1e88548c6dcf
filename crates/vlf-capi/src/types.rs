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
    /// The field exceeds a limit: a packed field that decodes to more than
    /// `VlfOpenOptions.max_unpacked_bytes`, or by default than the memory budget.
    VLF_ERR_LIMIT = 7,
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

/// How to open a field (`vlf_open_path_ex`, `vlf_open_memory_ex`). A NULL options pointer means
/// the defaults: every field zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct VlfOpenOptions {
    /// Refuse a packed field (`vlf-bake pack`) whose decoded size, which its section table states
    /// before anything is allocated, exceeds this many bytes, with `VLF_ERR_LIMIT`. 0: the
    /// default, three quarters of the memory the system reports available or what `ulimit -v`
    /// leaves, read at open (where the system reports neither, the format's own bound: a packed
    /// section decodes to at most a fixed multiple of its size). `UINT64_MAX`: the format's bound
    /// alone. Raw fields are mapped, not decoded, and are not affected.
    pub max_unpacked_bytes: u64,
}

/// The parameters a field was baked with (`formats/vlf.md` §5.2), as asked for and as chosen.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VlfParameters {
    /// The conservative margin μ, in world units.
    pub margin: f64,
    /// The size budget of automatic parameters, and the ceiling of explicit ones, in bytes.
    pub max_bytes: u64,
    /// The budget per triangle of automatic parameters, in bytes.
    pub max_bytes_per_triangle: u64,
    /// The lattice size N: the field stores `2N² + 1` directions.
    pub lattice_n: u32,
    /// The number of stored directions.
    pub directions: u32,
    /// Tiles per side of each direction's grid.
    pub tiles: u32,
    /// The leaf policy's target number of triangles per leaf.
    pub leaf_size: u32,
    /// The leaf policy's largest BSP depth.
    pub max_depth: u32,
    /// The directions asked for, or `VLF_AUTOMATIC` if the baker chose them.
    pub requested_directions: u32,
    /// The tiles asked for, or `VLF_AUTOMATIC` if the baker chose them.
    pub requested_tiles: u32,
    /// Zero (padding, named so that every byte of the struct is defined).
    pub reserved: u32,
}

/// `VlfParameters.requested_directions` and `requested_tiles`: chosen by the baker.
pub const VLF_AUTOMATIC: u32 = 0;

/// A surface of classical (Whitted) ray tracing, as a field's MATERIALS section stores it
/// (`formats/vlf.md` §5.10). Colours are linear RGB. `name` points into the open field and is
/// **not** NUL-terminated (`name_len` bytes, valid UTF-8, valid until `vlf_close`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VlfMaterial {
    /// The material's name in its input (may be empty), `name_len` bytes.
    pub name: *const c_char,
    /// Length of `name` in bytes.
    pub name_len: usize,
    /// The input (`VlfProvenance.input`'s file, by index in the field's inputs) it belongs to.
    pub input: u32,
    /// Its index in that input's materials (`VlfProvenance.material`).
    pub index: u32,
    /// Lambert reflectance.
    pub diffuse: [f32; 3],
    /// Phong exponent.
    pub shininess: f32,
    /// Colour of Phong highlights.
    pub specular: [f32; 3],
    /// Index of refraction of the inside (1 = rays pass unbent).
    pub ior: f32,
    /// Weight of the mirror-reflected ray.
    pub reflection: [f32; 3],
    /// Weight of the refracted ray.
    pub transmission: [f32; 3],
    /// Light the surface emits.
    pub emission: [f32; 3],
}

/// `VlfCamera.projection`: a pinhole (`yfov`, `aspect_ratio`).
pub const VLF_CAMERA_PERSPECTIVE: u32 = 1;
/// `VlfCamera.projection`: parallel rays (`xmag`, `ymag`).
pub const VLF_CAMERA_ORTHOGRAPHIC: u32 = 2;

/// A camera placed by a glTF node (`formats/vlf.md` §5.11), in world space. `name` as in
/// `VlfMaterial`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VlfCamera {
    /// The camera's name, else its node's (may be empty), `name_len` bytes.
    pub name: *const c_char,
    /// Length of `name` in bytes.
    pub name_len: usize,
    /// `VLF_CAMERA_PERSPECTIVE` or `VLF_CAMERA_ORTHOGRAPHIC`.
    pub projection: u32,
    /// Perspective: the vertical field of view in radians; 0 otherwise.
    pub yfov: f32,
    /// Perspective: width / height, or 0 if the file gives none; 0 otherwise.
    pub aspect_ratio: f32,
    /// Orthographic: half the view's width in world units; 0 otherwise.
    pub xmag: f32,
    /// Orthographic: half the view's height in world units; 0 otherwise.
    pub ymag: f32,
    /// The eye point.
    pub position: [f32; 3],
    /// The unit view direction.
    pub forward: [f32; 3],
    /// The unit up direction, orthogonal to `forward`.
    pub up: [f32; 3],
    /// The near plane's distance.
    pub znear: f32,
    /// The far plane's distance, or 0 for none (infinite).
    pub zfar: f32,
    /// The input it came from (by index in the field's inputs).
    pub input: u32,
    /// Its glTF camera index in that input.
    pub camera: u32,
    /// The glTF node that places it.
    pub node: u32,
}

/// `VlfLight.kind`: emits from `position` in all directions; intensity in candela.
pub const VLF_LIGHT_POINT: u32 = 1;
/// `VlfLight.kind`: emits from `position` in a cone around `direction`.
pub const VLF_LIGHT_SPOT: u32 = 2;
/// `VlfLight.kind`: parallel light along `direction`; intensity in lux.
pub const VLF_LIGHT_DIRECTIONAL: u32 = 3;

/// A `KHR_lights_punctual` light placed by a glTF node (`formats/vlf.md` §5.12), in world space.
/// `name` as in `VlfMaterial`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct VlfLight {
    /// The light's name, else its node's (may be empty), `name_len` bytes.
    pub name: *const c_char,
    /// Length of `name` in bytes.
    pub name_len: usize,
    /// `VLF_LIGHT_POINT`, `VLF_LIGHT_SPOT` or `VLF_LIGHT_DIRECTIONAL`.
    pub kind: u32,
    /// Position (point and spot lights).
    pub position: [f32; 3],
    /// Unit direction the light travels (spot and directional lights).
    pub direction: [f32; 3],
    /// Linear RGB.
    pub color: [f32; 3],
    /// Candela (point, spot) or lux (directional).
    pub intensity: f32,
    /// Distance beyond which the light has no effect, or 0 for none (unlimited).
    pub range: f32,
    /// Spot lights: half-angle of full intensity, in radians; 0 otherwise.
    pub inner_cone: f32,
    /// Spot lights: half-angle where the intensity reaches zero, in radians; 0 otherwise.
    pub outer_cone: f32,
    /// The input it came from (by index in the field's inputs).
    pub input: u32,
    /// Its `KHR_lights_punctual` light index in that input.
    pub light: u32,
    /// The glTF node that places it.
    pub node: u32,
}

/// An open field. Opaque: create it with `vlf_open_path` or `vlf_open_memory`, release it with
/// `vlf_close`. Immutable, so it may be queried from many threads at once.
pub struct VlfField {
    pub(crate) field: Field,
}
