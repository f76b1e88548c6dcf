//! Software prefetching: a hint to start loading a cache line that the query will read soon, so
//! that the misses of one ray (the next tile's block, the next leaf's refs) overlap with work
//! instead of following one another.

/// Asks the CPU to start loading the cache line that holds `value` into every cache level.
/// Only a hint: it changes no value and never faults.
#[inline(always)]
pub(crate) fn prefetch<T: ?Sized>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` needs SSE, which every x86-64 CPU has (the target's baseline). A
    // prefetch never faults and reads nothing into the program, and the address comes from a
    // reference, so it is valid anyway.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>((value as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
