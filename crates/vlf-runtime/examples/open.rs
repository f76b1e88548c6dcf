//! Opens a field many times and prints how long one open takes, then the time of the first query
//! after an open (which faults in the pages it reads). Opening maps the file and checks the header
//! and section table, so it takes the same time for a field of 1 MiB and one of many GiB
//! (`docs/benchmarks/big-field.sh` compares them).
//!
//! ```sh
//! cargo run --release -p vlf-runtime --example open -- scene.vlf [RUNS]
//! ```

use std::time::Instant;
use vlf_runtime::{Field, Ray};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: open FIELD [RUNS]")?;
    let runs: usize = args.next().map_or(Ok(1000), |r| r.parse())?;
    if runs == 0 {
        return Err("RUNS must be at least 1".into());
    }
    let mut open_us = Vec::with_capacity(runs);
    let mut first_query_us = Vec::with_capacity(runs);
    let mut bytes = 0;
    for _ in 0..runs {
        let start = Instant::now();
        let field = Field::open(&path)?;
        open_us.push(start.elapsed().as_secs_f64() * 1e6);
        // A ray through the centre of the scene.
        let (c, r) = field.bounding_sphere();
        let origin = [c[0] as f32, c[1] as f32, (c[2] + 2.0 * r) as f32];
        let start = Instant::now();
        std::hint::black_box(field.closest_hit(&Ray::new(origin, [0.0, 0.0, -1.0])));
        first_query_us.push(start.elapsed().as_secs_f64() * 1e6);
        bytes = field.len_bytes();
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{path}: {bytes} bytes; open: median {:.1} µs, first query after open: median {:.1} µs ({runs} runs)",
        median(&mut open_us),
        median(&mut first_query_us)
    );
    Ok(())
}
