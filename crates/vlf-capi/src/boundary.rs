//! The boundary with C: every argument checked before use (null, alignment, length, overlap),
//! every failure turned into a status and a per-thread message, and no panic let through.

use crate::types::VlfStatus::*;
use crate::types::*;
use std::cell::RefCell;
use std::ffi::CString;
use std::mem::MaybeUninit;
use std::panic::{AssertUnwindSafe, catch_unwind};
use vlf_runtime::{Field, FormatError, OpenError};

/// A failure on its way to C: the status and the message for `vlf_last_error_message`.
pub(crate) struct Failure {
    pub(crate) status: VlfStatus,
    pub(crate) message: String,
}

impl Failure {
    pub(crate) fn null(argument: &str) -> Failure {
        Failure { status: VLF_ERR_NULL_ARGUMENT, message: format!("argument `{argument}` is null") }
    }
    pub(crate) fn invalid(message: String) -> Failure {
        Failure { status: VLF_ERR_INVALID_ARGUMENT, message }
    }
    /// The failure with its message prefixed by what it is about (`instances[3]: …`).
    pub(crate) fn about(self, what: &str) -> Failure {
        Failure { message: format!("{what}: {}", self.message), ..self }
    }
}

impl From<OpenError> for Failure {
    fn from(e: OpenError) -> Failure {
        let status = match e {
            OpenError::Io { .. } => VLF_ERR_IO,
            OpenError::Format { error: FormatError::OutOfMemory { .. }, .. }
            | OpenError::Bytes(FormatError::OutOfMemory { .. }) => VLF_ERR_OUT_OF_MEMORY,
            OpenError::Format { error: FormatError::UnpackedTooLarge { .. }, .. }
            | OpenError::Bytes(FormatError::UnpackedTooLarge { .. }) => VLF_ERR_LIMIT,
            _ => VLF_ERR_FORMAT,
        };
        Failure { status, message: e.to_string() }
    }
}

thread_local! {
    /// The message of the last failed call on this thread.
    pub(crate) static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

pub(crate) fn set_last_error(message: String) {
    // A message never contains NUL, but a path could: show it rather than cut the message there.
    let message = CString::new(message.replace('\0', "\\0")).unwrap_or_default();
    // Once the thread's locals are destroyed (a call from a pthread key destructor, as the thread
    // exits), the message has nowhere to go: it is dropped, the status still tells the failure.
    let _ = LAST_ERROR.try_with(|e| *e.borrow_mut() = message);
}

/// What `vlf_last_error_message` returns once the thread's locals are destroyed.
pub(crate) const NO_MESSAGE_AT_EXIT: &std::ffi::CStr =
    c"(no message: the call was made while its thread was exiting, after its messages were freed)";

/// Runs the body of entry point `function`, turning its failure or a panic into a status and the
/// thread's last error message.
pub(crate) fn call(function: &str, body: impl FnOnce() -> Result<(), Failure>) -> VlfStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => VLF_OK,
        Ok(Err(f)) => {
            set_last_error(format!("{function}: {}", f.message));
            f.status
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .copied()
                .or_else(|| panic.downcast_ref::<String>().map(String::as_str))
                .unwrap_or("unknown panic");
            set_last_error(format!("{function}: internal error (a bug in the VLF library, please report it): {what}"));
            VLF_ERR_INTERNAL
        }
    }
}

/// `&*p`, or a failure naming `argument` if `p` is null or misaligned.
///
/// # Safety
/// A non-null, aligned `p` must point to a valid `T` that outlives `'a` and is not written
/// through another pointer meanwhile.
pub(crate) unsafe fn arg<'a, T>(p: *const T, argument: &str) -> Result<&'a T, Failure> {
    if p.is_null() {
        return Err(Failure::null(argument));
    }
    if !p.is_aligned() {
        return Err(Failure::invalid(format!("argument `{argument}` is not aligned to {} bytes", align_of::<T>())));
    }
    // SAFETY: non-null and aligned, checked above; validity is the caller's promise.
    Ok(unsafe { &*p })
}

/// `&mut *p`, or a failure naming `argument` if `p` is null or misaligned.
///
/// # Safety
/// A non-null, aligned `p` must be valid for writes of a `T` for `'a`, with no other reference to
/// that memory meanwhile. The memory need not be initialised (callers only write through it).
pub(crate) unsafe fn out<'a, T>(p: *mut T, argument: &str) -> Result<&'a mut MaybeUninit<T>, Failure> {
    if p.is_null() {
        return Err(Failure::null(argument));
    }
    if !p.is_aligned() {
        return Err(Failure::invalid(format!("argument `{argument}` is not aligned to {} bytes", align_of::<T>())));
    }
    // SAFETY: non-null and aligned, checked above; `MaybeUninit` asks nothing of the contents;
    // validity for writes is the caller's promise.
    Ok(unsafe { &mut *p.cast() })
}

/// [`out`] for an optional output: `None` if `p` is null, a failure if it is misaligned. Checked
/// with the other arguments, before the call changes anything.
///
/// # Safety
/// As for [`out`].
pub(crate) unsafe fn optional_out<'a, T>(p: *mut T, argument: &str) -> Result<Option<&'a mut MaybeUninit<T>>, Failure> {
    // SAFETY: the caller's promise, for a non-null `p`.
    if p.is_null() { Ok(None) } else { unsafe { out(p, argument) }.map(Some) }
}

/// The field behind a handle, or a failure if it is null.
///
/// # Safety
/// A non-null `field` must come from `vlf_open_*` and not have been closed.
pub(crate) unsafe fn field_arg<'a>(field: *const VlfField) -> Result<&'a Field, Failure> {
    // SAFETY: the caller's promise.
    Ok(&unsafe { arg(field, "field") }?.field)
}

/// The byte range `[p, p + len)` as integers, for overlap checks.
pub(crate) fn span<T>(p: *const T, n: usize) -> std::ops::Range<usize> {
    let start = p as usize;
    start..start.saturating_add(n.saturating_mul(size_of::<T>()))
}

/// A slice of `n` elements at `p`; `p` may be null when `n` is 0.
///
/// # Safety
/// When `n > 0`, a non-null aligned `p` must point to `n` valid, initialised elements that
/// outlive `'a` and are not written meanwhile.
pub(crate) unsafe fn slice_arg<'a, T>(p: *const T, n: usize, argument: &str) -> Result<&'a [T], Failure> {
    check_array(p, n, argument)?;
    if n == 0 {
        return Ok(&[]);
    }
    // SAFETY: non-null, aligned, and `n · size_of::<T>() ≤ isize::MAX` (checked); the caller
    // promises the elements are valid.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// Room for `n` elements at `p`, to be written; `p` may be null when `n` is 0.
///
/// # Safety
/// When `n > 0`, a non-null aligned `p` must be valid for writes of `n` elements for `'a`, with
/// no other reference to that memory meanwhile. The memory need not be initialised.
pub(crate) unsafe fn slice_out<'a, T>(
    p: *mut T,
    n: usize,
    argument: &str,
) -> Result<&'a mut [MaybeUninit<T>], Failure> {
    check_array(p, n, argument)?;
    if n == 0 {
        return Ok(&mut []);
    }
    // SAFETY: non-null, aligned, and `n · size_of::<T>() ≤ isize::MAX` (checked); validity for
    // writes is the caller's promise; `MaybeUninit` asks nothing of the contents.
    Ok(unsafe { std::slice::from_raw_parts_mut(p.cast(), n) })
}

/// Writes `values` to the start of `out`.
pub(crate) fn write_all<T: Copy>(out: &mut [MaybeUninit<T>], values: &[T]) {
    for (o, v) in out.iter_mut().zip(values) {
        o.write(*v);
    }
}

/// Checks that `p` can hold an array of `n` elements: anything goes for `n = 0`; otherwise `p` is
/// non-null and aligned, and the array's size fits in an `isize`.
pub(crate) fn check_array<T>(p: *const T, n: usize, argument: &str) -> Result<(), Failure> {
    if n == 0 {
        return Ok(());
    }
    if p.is_null() {
        return Err(Failure::null(argument));
    }
    if !p.is_aligned() {
        return Err(Failure::invalid(format!("argument `{argument}` is not aligned to {} bytes", align_of::<T>())));
    }
    if n.checked_mul(size_of::<T>()).is_none_or(|b| b > isize::MAX as usize) {
        return Err(Failure::invalid(format!("count {n} is too large for `{argument}`")));
    }
    Ok(())
}

pub(crate) fn check_disjoint(a: std::ops::Range<usize>, b: std::ops::Range<usize>, what: &str) -> Result<(), Failure> {
    if a.start < b.end && b.start < a.end {
        return Err(Failure::invalid(format!("{what} overlap")));
    }
    Ok(())
}

/// Checks that `index` is below `count` things the field has (`what`: `materials`, ...).
pub(crate) fn index_range(index: u32, count: usize, what: &str) -> Result<(), Failure> {
    if index as usize >= count {
        return Err(Failure::invalid(format!("index {index} is out of range: the field has {count} {what}")));
    }
    Ok(())
}

/// A count for C: the field's `count` things, which its sections bound far below `u32::MAX`.
pub(crate) fn count_u32(count: usize) -> u32 {
    u32::try_from(count).unwrap_or(u32::MAX)
}

pub(crate) fn triangle_range(field: &Field, prim: u32) -> Result<(), Failure> {
    let count = field.triangle_count();
    if prim >= count {
        return Err(Failure::invalid(format!("triangle id {prim} is out of range: the field has {count} triangles")));
    }
    Ok(())
}

/// The path named by the NUL-terminated `bytes` of a `path` argument (the platform's encoding).
#[cfg(unix)]
pub(crate) fn path_of(bytes: &[u8]) -> Result<&std::path::Path, Failure> {
    use std::os::unix::ffi::OsStrExt;
    Ok(std::path::Path::new(std::ffi::OsStr::from_bytes(bytes)))
}

/// The path named by the NUL-terminated `bytes` of a `path` argument (UTF-8 off Unix).
#[cfg(not(unix))]
pub(crate) fn path_of(bytes: &[u8]) -> Result<&std::path::Path, Failure> {
    std::str::from_utf8(bytes)
        .map(std::path::Path::new)
        .map_err(|_| Failure::invalid("argument `path` is not valid UTF-8".to_owned()))
}
