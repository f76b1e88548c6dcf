//! Every hit along a ray and hit counts: the runtime's `all_hits` and `hit_count` for C.

use crate::boundary::*;
use crate::types::*;
use vlf_runtime::Hit;

/// Traces `ray` for every hit on `[tmin, tmax]`: writes the `capacity` closest of them (all of
/// them if there are fewer) to `hits[0..*count]`, in order of `t` then triangle id, each triangle
/// once, and their number to `*count`. The same hits, bit for bit, as the Rust `FieldView::all_hits`
/// with `max_hits = capacity` (and as testing every triangle of the field). An invalid ray, or
/// `capacity = 0`, has none.
///
/// The search stops as soon as the `capacity` closest hits are known, so a small capacity is
/// cheaper than a large one. To learn how many hits there are in all, use `vlf_hit_count`.
/// Allocates a little scratch memory per call. Safe to call from many threads on the same field.
///
/// `hits` may be NULL when `capacity` is 0.
///
/// Returns `VLF_OK` (hits or none), `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT`
/// (misaligned pointers, `capacity` too large for memory); on an error nothing is written.
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `hits` NULL or room for
/// `capacity` hits; `count` NULL or writable; `hits` and `count` must not overlap.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_all_hits(
    field: *const VlfField,
    ray: *const VlfRay,
    hits: *mut VlfHit,
    capacity: usize,
    count: *mut usize,
) -> VlfStatus {
    call("vlf_all_hits", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray) = unsafe { (field_arg(field)?, arg(ray, "ray")?) };
        check_array(hits, capacity, "hits")?;
        check_disjoint(span(hits, capacity), span(count, 1), "arguments `hits` and `count`")?;
        // SAFETY: the caller's promises; they do not overlap (checked).
        let (hits, count) = unsafe { (slice_out(hits, capacity, "hits")?, out(count, "count")?) };
        let found = field.view().all_hits(bytemuck::cast_ref(ray), capacity);
        for (o, h) in hits.iter_mut().zip(&found) {
            o.write(bytemuck::cast(*h));
        }
        count.write(found.len());
        Ok(())
    })
}

/// Traces `n` rays for every hit, at most `max_hits` each: ray `i`'s hits go to
/// `hits[i * max_hits ..]` (the first `counts[i]` of those `max_hits` slots; the rest are left as
/// they were), in order of `t` then triangle id, as `vlf_all_hits` with `capacity = max_hits`
/// would write them. Runs on the calling thread; to use several cores, call it from several
/// threads on disjoint parts of the arrays.
///
/// `rays`, `hits` and `counts` may be NULL when they would hold nothing, and must not overlap.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (misaligned or
/// overlapping arrays, or `n · max_hits` too large); on an error nothing is written.
///
/// # Safety
/// `field` must be NULL or an open handle; `rays` must point to `n` rays, `hits` to room for
/// `n · max_hits` hits and `counts` to room for `n` counts (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_all_hits_batch(
    field: *const VlfField,
    rays: *const VlfRay,
    n: usize,
    max_hits: usize,
    hits: *mut VlfHit,
    counts: *mut usize,
) -> VlfStatus {
    call("vlf_all_hits_batch", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        let slots = n
            .checked_mul(max_hits)
            .ok_or_else(|| Failure::invalid(format!("{n} rays of {max_hits} hits each are too many for `hits`")))?;
        check_array(rays, n, "rays")?;
        check_array(hits, slots, "hits")?;
        check_array(counts, n, "counts")?;
        check_disjoint(span(rays, n), span(hits, slots), "arrays `rays` and `hits`")?;
        check_disjoint(span(rays, n), span(counts, n), "arrays `rays` and `counts`")?;
        check_disjoint(span(hits, slots), span(counts, n), "arrays `hits` and `counts`")?;
        // SAFETY: the caller's promises on the arrays; they do not overlap (checked).
        let (rays, hits, counts) =
            unsafe { (slice_arg(rays, n, "rays")?, slice_out(hits, slots, "hits")?, slice_out(counts, n, "counts")?) };
        let view = field.view();
        let mut scratch: Vec<Hit> = Vec::new();
        for (i, (ray, count)) in rays.iter().zip(counts).enumerate() {
            view.all_hits_into(bytemuck::cast_ref(ray), max_hits, &mut scratch);
            let slots = &mut hits[i * max_hits..(i + 1) * max_hits];
            for (o, h) in slots.iter_mut().zip(&scratch) {
                o.write(bytemuck::cast(*h));
            }
            count.write(scratch.len());
        }
        Ok(())
    })
}

/// The number of triangles `ray` hits on `[tmin, tmax]`, in `*count`: each triangle counted once,
/// however many of the field's leaves hold it (0 for an invalid ray). The number of hits
/// `vlf_all_hits` finds with an unlimited capacity; the parity of a count from a point tells
/// inside from outside of a closed mesh. Allocates a little scratch memory per call.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (a misaligned
/// pointer).
///
/// # Safety
/// `field` must be NULL or an open handle; `ray` NULL or a valid ray; `count` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_hit_count(field: *const VlfField, ray: *const VlfRay, count: *mut u32) -> VlfStatus {
    call("vlf_hit_count", || {
        // SAFETY: the caller's promises, argument by argument.
        let (field, ray, count) = unsafe { (field_arg(field)?, arg(ray, "ray")?, out(count, "count")?) };
        count.write(field.view().hit_count(bytemuck::cast_ref(ray)));
        Ok(())
    })
}

/// Counts the hits of `n` rays: `counts[i]` receives what `vlf_hit_count` gives for `rays[i]`.
/// Runs on the calling thread.
///
/// `rays` and `counts` may be NULL when `n` is 0, and must not overlap.
///
/// Returns `VLF_OK`, `VLF_ERR_NULL_ARGUMENT`, or `VLF_ERR_INVALID_ARGUMENT` (misaligned or
/// overlapping arrays, or `n` too large); on an error nothing is written.
///
/// # Safety
/// `field` must be NULL or an open handle; `rays` must point to `n` rays and `counts` to room for
/// `n` counts (or be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vlf_hit_counts(
    field: *const VlfField,
    rays: *const VlfRay,
    n: usize,
    counts: *mut u32,
) -> VlfStatus {
    call("vlf_hit_counts", || {
        // SAFETY: the caller's promise on `field`.
        let field = unsafe { field_arg(field) }?;
        check_array(rays, n, "rays")?;
        check_array(counts, n, "counts")?;
        check_disjoint(span(rays, n), span(counts, n), "arrays `rays` and `counts`")?;
        // SAFETY: the caller's promises on the arrays; they do not overlap (checked).
        let (rays, counts) = unsafe { (slice_arg(rays, n, "rays")?, slice_out(counts, n, "counts")?) };
        let view = field.view();
        let mut scratch: Vec<Hit> = Vec::new();
        for (ray, count) in rays.iter().zip(counts) {
            count.write(view.hit_count_into(bytemuck::cast_ref(ray), &mut scratch));
        }
        Ok(())
    })
}
