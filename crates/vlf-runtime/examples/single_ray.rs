//! Traces a rays file one ray at a time, `Field::closest_hit` (or `any_hit`) in a loop: the
//! single-ray query the peers benchmark times, in a program small enough to run under callgrind.
//!
//! ```text
//! cargo run --release -p vlf-runtime --example single_ray -- FIELD RAYS [--any] [--count N] [--rounds R] [--work] [--read]
//! ```
//!
//! `RAYS` is a file of 32-byte ray records (`formats/rays.md`). Each round traces the first `N`
//! rays of the file (all of them by default; it cycles through the file if `N` is larger) and the
//! program prints the median nanoseconds per ray over `R` rounds (default 5). Instructions per ray
//! under callgrind: run once with `--count N --rounds 1` and once with `--count 1 --rounds 1`, and
//! divide the difference by `N − 1` (`docs/benchmarks/single-ray.sh` does this). `--work` also
//! prints the work per ray of one more pass over the same rays (`*_counted`): tiles, leaves and
//! triangle tests. `--read` reads the field into memory (`Field::read`) instead of mapping it.

use std::time::Instant;
use vlf_runtime::{Field, Intersector, Ray, TraceStats};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: single_ray FIELD RAYS [--any] [--count N] [--rounds R] [--work] [--read]";
    let mut args = std::env::args().skip(1);
    let (field, rays) = (args.next().ok_or(usage)?, args.next().ok_or(usage)?);
    let (mut any, mut count, mut rounds, mut work, mut read) = (false, None, 5usize, false, false);
    while let Some(flag) = args.next() {
        match flag.as_str() {
            "--any" => any = true,
            "--work" => work = true,
            "--read" => read = true,
            "--count" => count = Some(args.next().ok_or(usage)?.parse::<usize>()?),
            "--rounds" => rounds = args.next().ok_or(usage)?.parse()?,
            _ => return Err(format!("unknown argument {flag}; {usage}").into()),
        }
    }
    let field = if read { Field::read(&field)? } else { Field::open(&field)? };
    let bytes = std::fs::read(&rays)?;
    let rays = match Ray::from_records(&bytes) {
        Some(rays) if !rays.is_empty() => rays,
        _ => return Err(format!("{rays}: {} bytes, not a whole number of 32-byte rays", bytes.len()).into()),
    };
    let count = count.unwrap_or(rays.len());
    if count == 0 || rounds == 0 {
        return Err("--count and --rounds must be at least 1".into());
    }
    let mut ns = Vec::with_capacity(rounds);
    let mut hits = 0;
    for _ in 0..rounds {
        hits = 0;
        let start = Instant::now();
        for ray in rays.iter().cycle().take(count) {
            hits += if any { field.any_hit(ray) } else { field.closest_hit(ray).is_some() } as usize;
        }
        ns.push(start.elapsed().as_secs_f64() * 1e9 / count as f64);
    }
    ns.sort_by(f64::total_cmp);
    println!("{count} rays, {hits} hits: median {:.1} ns per ray over {rounds} rounds", ns[rounds / 2]);
    if work {
        let mut stats = TraceStats::default();
        for ray in rays.iter().cycle().take(count) {
            if any {
                field.any_hit_counted(ray, &mut stats);
            } else {
                field.closest_hit_counted(ray, &mut stats);
            }
        }
        let per = |n: u64| n as f64 / count as f64;
        println!(
            "per ray: {:.2} tiles, {:.2} leaves, {:.2} triangle tests",
            per(stats.cells),
            per(stats.leaves),
            per(stats.triangle_tests)
        );
    }
    Ok(())
}
