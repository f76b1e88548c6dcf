//! The C API of the VLF runtime: open a baked visibility field and answer ray queries from C.
//!
//! This crate builds `libvlf.a` and `libvlf.so` (`libvlf.dylib`, `vlf.dll`) for C and C++
//! programs; the declarations are in `include/vlf.h`, which is generated from this file by
//! cbindgen and checked by a test (`tests/header.rs`). `docs/c-api.md` tells how to build and
//! link, and `examples/trace_rays.c` is a complete program.
//!
//! ```c
//! VlfField *field = NULL;
//! if (vlf_open_path("scene.vlf", &field) != VLF_OK) {
//!     fprintf(stderr, "%s\n", vlf_last_error_message());
//!     return 1;
//! }
//! VlfRay ray = {{0.0f, 0.1f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
//! VlfHit hit;
//! vlf_closest_hit(field, &ray, &hit);
//! if (hit.prim != VLF_NO_PRIM) printf("t = %g on triangle %u\n", hit.t, hit.prim);
//! vlf_close(field);
//! ```
//!
//! # Conventions
//! - Every function that can fail returns a [`VlfStatus`]: `VLF_OK` (zero) or an error code. On
//!   an error, [`vlf_last_error_message`] describes it in one line, naming the function, the
//!   argument or the file. Out-parameters are left untouched on an error unless a function says
//!   otherwise.
//! - Every pointer argument is checked: a null pointer gives `VLF_ERR_NULL_ARGUMENT`, a pointer
//!   not aligned for its type `VLF_ERR_INVALID_ARGUMENT`. Other invalid pointers (dangling, too
//!   short) cannot be detected and are undefined behaviour, as in any C API.
//! - No Rust panic crosses into C: should one happen (a bug), it is caught and reported as
//!   `VLF_ERR_INTERNAL`.
//! - A miss is not an error: the hit record is [`VLF_NO_PRIM`] with `t = +inf`, as in a hits file
//!   (`formats/rays.md`). An invalid ray (non-finite or zero direction, NaN bound,
//!   `tmin > tmax`) misses.
//!
//! # Thread safety
//! A `VlfField` is immutable once open: every query function may be called on the same field
//! from any number of threads at once, without locking. [`vlf_close`] must not run concurrently
//! with any other use of that field. The error message is per thread.
//!
//! # Lifetimes
//! A `VlfField` owns its mapping (or its copy of the bytes); the strings that
//! [`vlf_provenance`], [`vlf_material`], [`vlf_camera`] and [`vlf_light`] return point into it and
//! stay valid until [`vlf_close`].

#![deny(missing_docs)]

mod all_hits;
mod boundary;
mod dynamic;
mod info;
mod scene;
mod types;

pub use all_hits::*;
use boundary::*;
pub use dynamic::*;
pub use info::*;
pub use scene::*;
use std::ffi::{CStr, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use types::VlfStatus::*;
pub use types::*;
use vlf_runtime::{Hit, OpenOptions};

/// Rays per call of the batch query in `vlf_closest_hits` and `vlf_any_hits` (their answers pass
/// through a stack buffer of this many).
const ARRAY_CHUNK: usize = 256;

/// The version of this library, e.g. `"0.1.0"`: a static NUL-terminated string.
#[unsafe(no_mangle)]
pub extern "C" fn vlf_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// The name of a status code, e.g. `"VLF_ERR_IO"`, or `"unknown status"`: a static
/// NUL-terminated string.
#[unsafe(no_mangle)]
pub extern "C" fn vlf_status_name(status: i32) -> *const c_char {
    let name: &CStr = match status {
        0 => c"VLF_OK",
        1 => c"VLF_ERR_NULL_ARGUMENT",
        2 => c"VLF_ERR_INVALID_ARGUMENT",
        3 => c"VLF_ERR_IO",
        4 => c"VLF_ERR_FORMAT",
        5 => c"VLF_ERR_INTERNAL",
        6 => c"VLF_ERR_OUT_OF_MEMORY",
        7 => c"VLF_ERR_LIMIT",
        _ => c"unknown status",
    };
    name.as_ptr()
}

/// The message of the last call on this thread that failed: one line naming the function and
/// what went wrong (the argument, or the file and the fault), e.g.
/// `vlf_open_path: cannot read field scene.vlf: No such file or directory (os error 2)`.
/// An empty string if no call on this thread has failed.
///
/// The string belongs to the library. It is valid until the next failing call on the same
/// thread, or until the thread exits; copy it to keep it. Successful calls leave it unchanged,
/// so read it right after a call returns an error. Calls made while the thread is exiting (from a
/// thread-specific data destructor) keep no message: this then returns a fixed one saying so.
#[unsafe(no_mangle)]
pub extern "C" fn vlf_last_error_message() -> *const c_char {
    // The CString's heap buffer stays put until the next `set_last_error` on this thread.
    LAST_ERROR.try_with(|e| e.borrow().as_ptr()).unwrap_or(boundary::NO_MESSAGE_AT_EXIT.as_ptr())
}

/// Opens the field file at `path` (a NUL-terminated path in the platform's encoding) by
/// memory-mapping it, and stores the new handle in `*out`.
///
/// Checks the header, the section table and the content hash, and reads nothing else: the time
/// does not depend on the file's size. Queries then read the mapped bytes on demand. A packed
/// field (`vlf-bake pack`) is the exception: it is decoded into memory here, in time and memory
/// linear in its size.
///
/// The file must not be modified in place or truncated while the field is open (files written by
/// `vlf-bake` are replaced by renaming, which is safe). In-place changes give wrong answers; a
/// truncation makes the operating system raise `SIGBUS`. Use `vlf_open_memory` if that cannot be
/// ruled out.
///
/// Returns `VLF_OK`; `VLF_ERR_IO` if the file cannot be opened or mapped; `VLF_ERR_FORMAT` if it
/// is not a valid field (or a packed field that does not decode); `VLF_ERR_OUT_OF_MEMORY` if a
/// packed field's decoded bytes cannot be allocated; `VLF_ERR_LIMIT` if a packed field would
/// decode to more than the default cap (`vlf_open_path_ex`); `VLF_ERR_NULL_ARGUMENT`;
/// `VLF_ERR_INVALID_ARGUMENT` if `out` is misaligned. `*out` is set to NULL on failure (when `out`
/// itself is usable).
///
/// # Safety
/// `path` must be NULL or a NUL-terminated string; `out` must be NULL or valid for writing a
/// pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_open_path(path: *const c_char, out: *mut *mut VlfField) -> VlfStatus {
    // SAFETY: the caller's promises; no options.
    unsafe { open_path("vlf_open_path", path, std::ptr::null(), out) }
}

/// `vlf_open_path` with options: `options` NULL gives the defaults (as `vlf_open_path`), else
/// `options->max_unpacked_bytes` caps the memory a packed field may be decoded into (0: the
/// default, three quarters of the memory the system reports available, or what `ulimit -v`
/// leaves; `UINT64_MAX`: the format's own bound alone). A packed field over the cap is refused
/// before anything is allocated.
///
/// Returns what `vlf_open_path` returns, and `VLF_ERR_LIMIT` for a packed field that decodes to
/// more than the cap; `VLF_ERR_INVALID_ARGUMENT` if `options` is misaligned. `*out`
/// is set to NULL on failure.
///
/// # Safety
/// As `vlf_open_path`; `options` must be NULL or point to a `VlfOpenOptions`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_open_path_ex(
    path: *const c_char,
    options: *const VlfOpenOptions,
    out: *mut *mut VlfField,
) -> VlfStatus {
    // SAFETY: the caller's promises.
    unsafe { open_path("vlf_open_path_ex", path, options, out) }
}

/// The runtime's options for `options`: the defaults when it is NULL.
///
/// # Safety
/// `options` must be NULL or point to a `VlfOpenOptions`.
unsafe fn open_options(options: *const VlfOpenOptions) -> Result<OpenOptions, Failure> {
    let mut o = OpenOptions::new();
    if !options.is_null() {
        // SAFETY: the caller's promise.
        let given = unsafe { arg(options, "options") }?;
        if given.max_unpacked_bytes != 0 {
            o.max_unpacked_bytes(given.max_unpacked_bytes);
        }
    }
    Ok(o)
}

/// The body of `vlf_open_path` and `vlf_open_path_ex`, reporting as `function`.
///
/// # Safety
/// As `vlf_open_path_ex`.
unsafe fn open_path(
    function: &str,
    path: *const c_char,
    options: *const VlfOpenOptions,
    out: *mut *mut VlfField,
) -> VlfStatus {
    call(function, || {
        // SAFETY: the caller's promise on `out`.
        let out = unsafe { boundary::out(out, "out") }?;
        out.write(std::ptr::null_mut());
        if path.is_null() {
            return Err(Failure::null("path"));
        }
        // SAFETY: the caller's promise on `options`.
        let options = unsafe { open_options(options) }?;
        // SAFETY: non-null, and NUL-terminated by the caller's promise.
        let bytes = unsafe { CStr::from_ptr(path) }.to_bytes();
        let field = options.open(path_of(bytes)?)?;
        out.write(Box::into_raw(Box::new(VlfField { field })));
        Ok(())
    })
}

/// Opens a field from `len` bytes at `data` and stores the new handle in `*out`.
///
/// The bytes are **copied** once into a buffer the field owns (aligned as the sections need; a
/// packed field is decoded into it), so `data` may be freed or reused as soon as this returns,
/// and nothing can change the field's bytes afterwards. Time and memory are linear in `len`; for
/// large files prefer `vlf_open_path`, which maps the file instead.
///
/// Returns `VLF_OK`; `VLF_ERR_FORMAT` if the bytes are not a valid field;
/// `VLF_ERR_OUT_OF_MEMORY` if the copy cannot be allocated; `VLF_ERR_LIMIT` if a packed field
/// would decode to more than the default cap (`vlf_open_path_ex`); `VLF_ERR_NULL_ARGUMENT` if `data` or
/// `out` is NULL; `VLF_ERR_INVALID_ARGUMENT` if `out` is misaligned or `len` is too large. `*out`
/// is set to NULL on failure (when `out` itself is usable).
///
/// # Safety
/// `data` must be NULL or point to `len` readable bytes; `out` must be NULL or valid for writing
/// a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_open_memory(data: *const c_void, len: usize, out: *mut *mut VlfField) -> VlfStatus {
    // SAFETY: the caller's promises; no options.
    unsafe { open_memory("vlf_open_memory", data, len, std::ptr::null(), out) }
}

/// `vlf_open_memory` with options, as `vlf_open_path_ex`: `options` NULL gives the defaults, else
/// `options->max_unpacked_bytes` caps the memory a packed field may be decoded into (0: the
/// default, as for `vlf_open_path_ex`).
///
/// Returns what `vlf_open_memory` returns, and `VLF_ERR_LIMIT` for a packed field that decodes to
/// more than the cap; `VLF_ERR_INVALID_ARGUMENT` if `options` is misaligned. `*out`
/// is set to NULL on failure.
///
/// # Safety
/// As `vlf_open_memory`; `options` must be NULL or point to a `VlfOpenOptions`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_open_memory_ex(
    data: *const c_void,
    len: usize,
    options: *const VlfOpenOptions,
    out: *mut *mut VlfField,
) -> VlfStatus {
    // SAFETY: the caller's promises.
    unsafe { open_memory("vlf_open_memory_ex", data, len, options, out) }
}

/// The body of `vlf_open_memory` and `vlf_open_memory_ex`, reporting as `function`.
///
/// # Safety
/// As `vlf_open_memory_ex`.
unsafe fn open_memory(
    function: &str,
    data: *const c_void,
    len: usize,
    options: *const VlfOpenOptions,
    out: *mut *mut VlfField,
) -> VlfStatus {
    call(function, || {
        // SAFETY: the caller's promise on `out`.
        let out = unsafe { boundary::out(out, "out") }?;
        out.write(std::ptr::null_mut());
        if data.is_null() {
            return Err(Failure::null("data"));
        }
        // SAFETY: the caller's promise on `options`.
        let options = unsafe { open_options(options) }?;
        // SAFETY: byte pointers need no alignment; `len` readable bytes by the caller's promise.
        let bytes = unsafe { slice_arg(data.cast::<u8>(), len, "data") }?;
        let field = options.from_bytes(bytes)?;
        out.write(Box::into_raw(Box::new(VlfField { field })));
        Ok(())
    })
}

/// Closes a field: unmaps or frees its bytes. The handle and every provenance string obtained
/// from it become invalid. NULL is ignored. Must not run concurrently with any other use of the
/// same field.
///
/// # Safety
/// `field` must be NULL or a handle from `vlf_open_*` that has not been closed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_close(field: *mut VlfField) {
    if field.is_null() {
        return;
    }
    // Dropping a Field unmaps or frees memory; it cannot panic, but no unwind may reach C.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a live handle from `Box::into_raw` in `vlf_open_*`, closed once (the caller's
        // promise).
        drop(unsafe { Box::from_raw(field) });
    }));
}

/// Traces `ray` and writes its closest hit on `[tmin, tmax]` to `*hit` (the miss record if
/// nothing is hit). The same answer, bit for bit, as the Rust `Field::closest_hit`.
///
/// Constant time to find the ray's beams, then a walk over the tiles the ray crosses; allocates
/// nothing. Safe to call from many threads on the same field.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a
/// misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `hit` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_closest_hit(field: *const VlfField, ray: *const VlfRay, hit: *mut VlfHit) -> VlfStatus {
    call("vlf_closest_hit", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray, hit) = unsafe { (field_arg(field)?, arg(ray, "ray")?, out(hit, "hit")?) };
        let h = Hit::record(field.closest_hit(bytemuck::cast_ref(ray)));
        hit.write(bytemuck::cast(h));
        Ok(())
    })
}

/// Traces `ray` for any hit on `[tmin, tmax]` (a shadow ray): writes 1 to `*hit` if something is
/// hit, 0 if not. Stops at the first hit found, so it is never slower than `vlf_closest_hit`.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a
/// misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `hit` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_any_hit(field: *const VlfField, ray: *const VlfRay, hit: *mut u8) -> VlfStatus {
    call("vlf_any_hit", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray, hit) = unsafe { (field_arg(field)?, arg(ray, "ray")?, out(hit, "hit")?) };
        hit.write(field.any_hit(bytemuck::cast_ref(ray)) as u8);
        Ok(())
    })
}

/// The point the field's triangles are stored relative to (the centre of its scene), in world
/// coordinates, written to `origin[0..3]`. Rays given relative to it (`vlf_closest_hit_local`,
/// `vlf_any_hit_local`) keep their precision in scenes far from the world's origin, where a
/// float world origin cannot be precise.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `origin` NULL or room for 3 doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_origin(field: *const VlfField, origin: *mut f64) -> VlfStatus {
    call("vlf_origin", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, origin) = unsafe { (field_arg(field)?, slice_out(origin, 3, "origin")?) };
        write_all(origin, &field.origin());
        Ok(())
    })
}

/// `vlf_closest_hit` for a ray whose origin is given relative to `vlf_origin` (subtract it, in
/// double precision, before rounding to float). `t`, `u`, `v` and `prim` mean what they mean for
/// world rays; the same answer, bit for bit, as the Rust `Field::closest_hit_local`.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a
/// misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `hit` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_closest_hit_local(
    field: *const VlfField,
    ray: *const VlfRay,
    hit: *mut VlfHit,
) -> VlfStatus {
    call("vlf_closest_hit_local", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray, hit) = unsafe { (field_arg(field)?, arg(ray, "ray")?, out(hit, "hit")?) };
        let h = Hit::record(field.closest_hit_local(bytemuck::cast_ref(ray)));
        hit.write(bytemuck::cast(h));
        Ok(())
    })
}

/// `vlf_any_hit` for a ray whose origin is given relative to `vlf_origin`.
///
/// Returns `VLF_OK` (hit or miss), `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a
/// misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `hit` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_any_hit_local(field: *const VlfField, ray: *const VlfRay, hit: *mut u8) -> VlfStatus {
    call("vlf_any_hit_local", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray, hit) = unsafe { (field_arg(field)?, arg(ray, "ray")?, out(hit, "hit")?) };
        hit.write(field.any_hit_local(bytemuck::cast_ref(ray)) as u8);
        Ok(())
    })
}

/// Traces `n` rays: `hits[i]` receives the closest hit of `rays[i]` (the miss record if none), as
/// `vlf_closest_hit` would, bit for bit. Rays whose neighbours start far from them are traced
/// several at a time, interleaved so that their cache misses overlap (`Field::closest_hits`). Runs on the calling thread; to use several cores, call it from several
/// threads on disjoint parts of the arrays.
///
/// `rays` and `hits` may be NULL when `n` is 0, and must not overlap.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (misaligned or
/// overlapping arrays, or `n` too large); on an error nothing is written.
///
/// # Safety
/// `field` must be NULL or an open handle; `rays` must point to `n` rays and `hits` to room for
/// `n` hits (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_closest_hits(
    field: *const VlfField,
    rays: *const VlfRay,
    n: usize,
    hits: *mut VlfHit,
) -> VlfStatus {
    call("vlf_closest_hits", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(rays, n, "rays")?;
        check_array(hits, n, "hits")?;
        check_disjoint(span(rays, n), span(hits, n), "arrays `rays` and `hits`")?;
        // SAFETY: the caller's promises on the arrays; they do not overlap (checked).
        let (rays, hits) = unsafe { (slice_arg(rays, n, "rays")?, slice_out(hits, n, "hits")?) };
        // Through the batch query (rays that start far apart interleaved), a stack buffer at a time.
        let mut buffer = [Hit::MISS; ARRAY_CHUNK];
        for (rays, hits) in rays.chunks(ARRAY_CHUNK).zip(hits.chunks_mut(ARRAY_CHUNK)) {
            let buffer = &mut buffer[..rays.len()];
            field.closest_hits(bytemuck::cast_slice(rays), buffer);
            write_all(hits, bytemuck::cast_slice(buffer));
        }
        Ok(())
    })
}

/// Traces `n` rays for any hit: `hits[i]` receives 1 if `rays[i]` hits something, 0 if not, as
/// `vlf_any_hit` would (interleaved as `vlf_closest_hits`). Runs on the calling thread.
///
/// `rays` and `hits` may be NULL when `n` is 0, and must not overlap.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (misaligned or
/// overlapping arrays, or `n` too large); on an error nothing is written.
///
/// # Safety
/// `field` must be NULL or an open handle; `rays` must point to `n` rays and `hits` to `n`
/// writable bytes (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_any_hits(
    field: *const VlfField,
    rays: *const VlfRay,
    n: usize,
    hits: *mut u8,
) -> VlfStatus {
    call("vlf_any_hits", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(rays, n, "rays")?;
        check_array(hits, n, "hits")?;
        check_disjoint(span(rays, n), span(hits, n), "arrays `rays` and `hits`")?;
        // SAFETY: the caller's promises on the arrays; they do not overlap (checked).
        let (rays, hits) = unsafe { (slice_arg(rays, n, "rays")?, slice_out(hits, n, "hits")?) };
        let mut buffer = [false; ARRAY_CHUNK];
        for (rays, hits) in rays.chunks(ARRAY_CHUNK).zip(hits.chunks_mut(ARRAY_CHUNK)) {
            let buffer = &mut buffer[..rays.len()];
            field.any_hits(bytemuck::cast_slice(rays), buffer);
            for (hit, &any) in hits.iter_mut().zip(buffer.iter()) {
                hit.write(any as u8);
            }
        }
        Ok(())
    })
}

/// The number of triangles in the field, in `*count`. Triangle ids run from 0 to `count − 1`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_triangle_count(field: *const VlfField, count: *mut u32) -> VlfStatus {
    call("vlf_triangle_count", || {
        // SAFETY: the caller's promises.
        let (field, count) = unsafe { (field_arg(field)?, out(count, "count")?) };
        count.write(field.triangle_count());
        Ok(())
    })
}

/// The vertices of triangle `prim` in world coordinates (rounded to f32), in `vertices[0..9]`:
/// `v0.x, v0.y, v0.z, v1.x, …, v2.z`.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` if `prim` is not
/// below the triangle count or a pointer is misaligned.
///
/// # Safety
/// `field` must be NULL or an open handle; `vertices` NULL or room for 9 floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_triangle(field: *const VlfField, prim: u32, vertices: *mut f32) -> VlfStatus {
    call("vlf_triangle", || {
        // SAFETY: the caller's promises.
        let (field, vertices) = unsafe { (field_arg(field)?, slice_out(vertices, 9, "vertices")?) };
        triangle_range(field, prim)?;
        let t = field.triangle(prim).ok_or_else(|| Failure::invalid(format!("no triangle {prim}")))?;
        let world: Vec<f32> = t.as_flattened().iter().map(|&c| c as f32).collect();
        write_all(vertices, &world);
        Ok(())
    })
}

/// Where triangle `prim` came from, in `*provenance`. Its strings point into the field and stay
/// valid until `vlf_close`; they are not NUL-terminated.
///
/// Returns `VLF_OK`; `VLF_ERR_INVALID_ARGUMENT` if `prim` is not below the triangle count (or a
/// pointer is misaligned); `VLF_ERR_FORMAT` if the field's provenance of that triangle is corrupt
/// (a reference out of bounds or a name that is not UTF-8: the open checks do not read that deep);
/// `VLF_ERR_NULL_ARGUMENT`.
///
/// # Safety
/// `field` must be NULL or an open handle; `provenance` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_provenance(
    field: *const VlfField,
    prim: u32,
    provenance: *mut VlfProvenance,
) -> VlfStatus {
    call("vlf_provenance", || {
        // SAFETY: the caller's promises.
        let (field, provenance) = unsafe { (field_arg(field)?, out(provenance, "provenance")?) };
        triangle_range(field, prim)?;
        let p = field.provenance(prim).ok_or_else(|| Failure {
            status: VLF_ERR_FORMAT,
            message: format!("the provenance of triangle {prim} is corrupt (run `vlf-bake dump --verify`)"),
        })?;
        provenance.write(VlfProvenance {
            input: p.input.as_ptr().cast(),
            input_len: p.input.len(),
            name: p.name.as_ptr().cast(),
            name_len: p.name.len(),
            kind: p.kind,
            mesh: p.mesh,
            primitive: p.primitive,
            node: p.node.unwrap_or(VLF_NO_INDEX),
            material: p.material.unwrap_or(VLF_NO_INDEX),
            index: p.index,
        });
        Ok(())
    })
}

/// The field's content hash (`formats/vlf.md` §3.1), 32 bytes written to `hash[0..32]`. It
/// identifies the file's exact bytes; `vlf-bake dump` prints it in hex.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned handle).
///
/// # Safety
/// `field` must be NULL or an open handle; `hash` NULL or room for 32 bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_content_hash(field: *const VlfField, hash: *mut u8) -> VlfStatus {
    call("vlf_content_hash", || {
        // SAFETY: the caller's promises.
        let (field, hash) = unsafe { (field_arg(field)?, slice_out(hash, 32, "hash")?) };
        write_all(hash, &field.content_hash());
        Ok(())
    })
}

/// The field's input hash (`formats/vlf.md` §3.2), 32 bytes written to `hash[0..32]`. It
/// identifies the bake's inputs and parameters: two fields baked from the same meshes with the
/// same parameters share it.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned handle).
///
/// # Safety
/// `field` must be NULL or an open handle; `hash` NULL or room for 32 bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_input_hash(field: *const VlfField, hash: *mut u8) -> VlfStatus {
    call("vlf_input_hash", || {
        // SAFETY: the caller's promises.
        let (field, hash) = unsafe { (field_arg(field)?, slice_out(hash, 32, "hash")?) };
        write_all(hash, &field.input_hash());
        Ok(())
    })
}

/// The scene's bounding sphere: centre in `center[0..3]`, radius in `*radius`. Every triangle
/// lies inside it; use it to place a camera.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned pointer,
/// or `radius` inside `center`).
///
/// # Safety
/// `field` must be NULL or an open handle; `center` NULL or room for 3 doubles; `radius` NULL or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_bounding_sphere(field: *const VlfField, center: *mut f64, radius: *mut f64) -> VlfStatus {
    call("vlf_bounding_sphere", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(center, 3, "center")?;
        check_array(radius, 1, "radius")?;
        check_disjoint(span(center, 3), span(radius, 1), "arguments `center` and `radius`")?;
        // SAFETY: the caller's promises; the outputs do not overlap (checked).
        let (center, radius) = unsafe { (slice_out(center, 3, "center")?, out(radius, "radius")?) };
        let (c, r) = field.bounding_sphere();
        write_all(center, &c);
        radius.write(r);
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn last_error() -> String {
        // SAFETY: `vlf_last_error_message` returns a NUL-terminated string owned by this thread.
        unsafe { CStr::from_ptr(vlf_last_error_message()) }.to_string_lossy().into_owned()
    }

    #[test]
    fn a_panic_becomes_an_internal_error() {
        let status = call("vlf_test", || panic!("boom {}", 42));
        assert_eq!(status, VLF_ERR_INTERNAL);
        assert_eq!(last_error(), "vlf_test: internal error (a bug in the VLF library, please report it): boom 42");
    }

    #[test]
    fn failures_set_the_message_and_successes_keep_it() {
        assert_eq!(call("vlf_test", || Err(Failure::null("thing"))), VLF_ERR_NULL_ARGUMENT);
        assert_eq!(last_error(), "vlf_test: argument `thing` is null");
        assert_eq!(call("vlf_test", || Ok(())), VLF_OK);
        assert_eq!(last_error(), "vlf_test: argument `thing` is null");
        // A NUL inside a message (from a path) is shown, not allowed to cut the message short.
        assert_eq!(call("vlf_test", || Err(Failure::invalid("a\0b".into()))), VLF_ERR_INVALID_ARGUMENT);
        assert_eq!(last_error(), "vlf_test: a\\0b");
    }

    #[test]
    fn status_names_match_the_enum() {
        for s in [
            VLF_OK,
            VLF_ERR_NULL_ARGUMENT,
            VLF_ERR_INVALID_ARGUMENT,
            VLF_ERR_IO,
            VLF_ERR_FORMAT,
            VLF_ERR_INTERNAL,
            VLF_ERR_OUT_OF_MEMORY,
            VLF_ERR_LIMIT,
        ] {
            // SAFETY: static NUL-terminated strings.
            let name = unsafe { CStr::from_ptr(vlf_status_name(s as i32)) };
            assert_eq!(name.to_str().unwrap(), format!("{s:?}"));
        }
    }

    #[test]
    fn open_errors_map_to_codes() {
        let mut field: *mut VlfField = std::ptr::NonNull::dangling().as_ptr();
        let bytes = [0u8; 200];
        // SAFETY: valid pointers and lengths.
        let status = unsafe { vlf_open_memory(bytes.as_ptr().cast(), bytes.len(), &mut field) };
        assert_eq!((status, field.is_null()), (VLF_ERR_FORMAT, true));
        assert!(last_error().starts_with("vlf_open_memory: not a valid field: bad magic"), "{}", last_error());
        // SAFETY: a NUL-terminated path.
        let status = unsafe { vlf_open_path(c"/nonexistent/field.vlf".as_ptr(), &mut field) };
        assert_eq!((status, field.is_null()), (VLF_ERR_IO, true));
        assert!(last_error().contains("/nonexistent/field.vlf"), "{}", last_error());
    }
}
