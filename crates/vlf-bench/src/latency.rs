//! How long one load waits when it depends on the one before (a pointer chase): the price of each
//! miss in a ray's chain (tile entry → block header → a leaf's refs → its triangles), which no
//! amount of work per ray can hide. `examples/memory_latency.rs` prints it for working sets of
//! several sizes; the peers benchmark records it before timing each ray set, because on a
//! virtual machine whose host shares its last-level cache it moves from run to run, and the
//! rays that wait on memory (incoherent ones) move with it.

use std::time::Instant;
use vlf_bake::generate::Rng;
use vlf_format::AlignedBytes;

/// Loads followed per timed pass.
const LOADS: usize = 2_000_000;

/// The working set the peers benchmark chases before each ray set, in MiB: about the size of the
/// random 100K scenes' fields.
pub const PEERS_WORKING_SET_MIB: u64 = 64;

/// The median nanoseconds per load, over five passes of two million loads, of a random cycle
/// through the 64-byte lines of a buffer of `bytes` bytes (at least one line). The buffer is
/// `vlf_format::AlignedBytes`, which is what a field read into memory sits in (on 2 MiB pages
/// where the kernel grants them, as a mapped field does), so TLB misses cost what they cost a
/// query.
pub fn chase(bytes: u64) -> anyhow::Result<f64> {
    let lines = (bytes / 64).max(1) as usize;
    let mut buffer = AlignedBytes::zeroed(lines as u64 * 64)?;
    // A random cyclic order of the lines (Fisher–Yates with the scene generators' seeded
    // generator), each line holding the index of the next in its first eight bytes.
    let mut order: Vec<u64> = (0..lines as u64).collect();
    let mut rng = Rng::new(1);
    for i in (1..lines).rev() {
        order.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let words: &mut [u64] = bytemuck::cast_slice_mut(buffer.as_bytes_mut());
    for (i, &line) in order.iter().enumerate() {
        words[8 * line as usize] = order[(i + 1) % lines];
    }
    let words: &[u64] = bytemuck::cast_slice(buffer.as_bytes());
    let mut at = order[0];
    // One pass untimed, so that pages are mapped and what fits is cached.
    for _ in 0..lines.min(LOADS) {
        at = words[8 * at as usize];
    }
    let mut times = Vec::new();
    for _ in 0..5 {
        let start = Instant::now();
        for _ in 0..LOADS {
            at = words[8 * at as usize];
        }
        times.push(start.elapsed().as_secs_f64() * 1e9 / LOADS as f64);
    }
    std::hint::black_box(at);
    Ok(crate::median(&mut times))
}

/// Steps of [`core_probe_ns`]'s computation per timed pass.
const PROBE_STEPS: u64 = 50_000;

/// How fast this core computes right now: the median nanoseconds per step, over three passes, of a
/// fixed computation of eight independent integer streams and four floating-point ones (about 60
/// independent operations a step, nothing from memory). On a virtual machine the host can lend
/// the physical core to someone else for seconds at a time; this computation, which keeps the core's
/// units as busy as a field query does, then slows down with the queries, so that a timed round
/// can be told to have fallen in such a spell (`docs/benchmarks/where-the-time-goes.md`,
/// 2026-12-07 08:15: in them the field lost 25–45% of its speed and Embree 10–25%).
pub fn core_probe_ns() -> f64 {
    let mut times = Vec::with_capacity(3);
    let mut state = [0x9e37_79b9_7f4a_7c15u64, 2, 3, 4, 5, 6, 7, 8];
    let mut acc = [1.0f64; 4];
    for _ in 0..3 {
        let start = Instant::now();
        for _ in 0..PROBE_STEPS {
            for x in state.iter_mut() {
                *x ^= *x << 13;
                *x ^= *x >> 7;
                *x ^= *x << 17;
            }
            for (a, x) in acc.iter_mut().zip(state) {
                *a = *a * 0.999_999 + (x & 0xff) as f64;
            }
        }
        times.push(start.elapsed().as_secs_f64() * 1e9 / PROBE_STEPS as f64);
        std::hint::black_box((&mut state, &mut acc));
    }
    crate::median(&mut times)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chase_through_a_small_buffer_takes_a_positive_finite_time() {
        let ns = chase(64 << 10).expect("a 64 KiB buffer");
        assert!(ns.is_finite() && ns > 0.0, "{ns}");
        // A buffer smaller than a line still holds one line, which points at itself.
        assert!(chase(8).expect("one line") > 0.0);
    }

    #[test]
    fn the_core_probe_takes_a_positive_finite_time() {
        let ns = core_probe_ns();
        assert!(ns.is_finite() && ns > 0.0, "{ns}");
    }
}
