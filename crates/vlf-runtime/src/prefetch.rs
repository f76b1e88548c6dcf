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

/// Starts loading `lines` cache lines `step` bytes apart from the one that holds `first` (a
/// negative `step` walks back). The addresses past the first need not lie in any object: a
/// prefetch of an address that is not mapped is dropped, never faults, so no bounds are checked.
#[inline(always)]
pub(crate) fn prefetch_lines<T>(first: &T, lines: usize, step: isize) {
    #[cfg(target_arch = "x86_64")]
    {
        let base = (first as *const T).cast::<i8>();
        for i in 0..lines {
            // SAFETY: as in `prefetch`; `wrapping_offset` computes the address without claiming
            // that it points into `first`, and the prefetch neither reads it into the program
            // nor faults on it.
            unsafe {
                use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
                _mm_prefetch::<_MM_HINT_T0>(base.wrapping_offset(step * i as isize));
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (first, lines, step);
}
