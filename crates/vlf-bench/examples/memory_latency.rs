//! How long one load waits on this machine when it depends on the one before (a pointer chase):
//! the price of each miss in a ray's chain (tile entry → block header → a leaf's refs → its
//! triangles), which no amount of work per ray can hide.
//!
//! ```text
//! cargo run --release -p vlf-bench --example memory_latency -- [MIB...]
//! ```
//!
//! For each working set (default 1, 4, 16, 64, 256 MiB), the 64-byte lines of a buffer are linked
//! into one cycle in a random order and followed; the program prints the median nanoseconds per
//! load over five passes of two million loads. The buffer is `vlf_format::AlignedBytes`, which is
//! what a field read into memory sits in (on 2 MiB pages where the kernel grants them, as a mapped
//! field does), so TLB misses cost what they cost a query.

use std::time::Instant;
use vlf_bake::generate::Rng;
use vlf_format::AlignedBytes;

/// Loads followed per timed pass.
const LOADS: usize = 2_000_000;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes: Vec<u64> = match std::env::args().skip(1).map(|a| a.parse::<u64>()).collect::<Result<Vec<_>, _>>()? {
        sizes if sizes.is_empty() => vec![1, 4, 16, 64, 256],
        sizes => sizes,
    };
    println!("| working set | ns per dependent load |");
    println!("| ---: | ---: |");
    for mib in sizes {
        if !(1..=65536).contains(&mib) {
            return Err(format!("{mib} MiB: give working sets from 1 to 65536 MiB").into());
        }
        println!("| {mib} MiB | {:.1} |", chase(mib << 20)?);
    }
    Ok(())
}

/// The median nanoseconds per load of a random cycle through the lines of `bytes` bytes.
fn chase(bytes: u64) -> Result<f64, Box<dyn std::error::Error>> {
    let lines = (bytes / 64) as usize;
    let mut buffer = AlignedBytes::zeroed(bytes)?;
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
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}
