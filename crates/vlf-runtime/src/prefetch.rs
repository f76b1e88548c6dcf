//! Software prefetching: a hint to start loading a cache line that the query will read soon, so
//! that the misses of one ray (the next tile's block, the next leaf's refs) overlap with work
//! instead of following one another.

/// Asks the CPU to start loading the cache line that holds `value` into every cache level.
/// Only a hint: it changes no value and never faults.
#[inline(always)]
pub(crate) fn prefetch<T: ?Sized>(value: &T) {
    prefetch_address((value as *const T).cast());
}

/// Starts loading `lines` cache lines `step` bytes apart from the one that holds `first` (a
/// negative `step` walks back). The addresses past the first need not lie in any object (see
/// [`prefetch_address`]), so none is checked against a bound.
#[inline(always)]
pub(crate) fn prefetch_lines<T>(first: &T, lines: usize, step: isize) {
    let base = (first as *const T).cast::<i8>();
    for i in 0..lines {
        // `wrapping_offset`: the address is computed, never dereferenced.
        prefetch_address(base.wrapping_offset(step * i as isize));
    }
}

/// The prefetch instruction on `address`, whatever it points to.
#[inline(always)]
fn prefetch_address(address: *const i8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `_mm_prefetch` needs SSE, which every x86-64 CPU has (the target's baseline). A
    // prefetch reads nothing into the program and never faults, whatever the address: one that
    // is not mapped, or not the program's, is dropped. So any pointer will do, in bounds or not.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(address);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}
