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
//! load over five passes of two million loads ([`vlf_bench::latency::chase`]).

use vlf_bench::latency::chase;

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
