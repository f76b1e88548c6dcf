//! The batch queries' three ways of tracing a ray file: one ray after another
//! ([`Interleave::Never`]), several interleaved ([`Interleave::Always`]), and the automatic
//! choice between the two that `closest_hits` and `any_hits` make ([`Interleave::Auto`]):
//! whether the automatic choice picks the faster one.
//!
//! ```text
//! cargo run --release -p vlf-runtime --example batch_choice -- FIELD RAYS...
//! ```
//!
//! Each `RAYS` file (32-byte records, `formats/rays.md`; a name containing `shadow` asks any hit,
//! the others the closest hit) is traced in chunks of 1,024 rays, five rounds per way; the program
//! prints the median nanoseconds per ray of each way. `docs/benchmarks/single-ray-sets.sh` writes
//! the ray files (primary, incoherent, shadow, ambient-occlusion and bounce rays).

use std::time::Instant;
use vlf_runtime::{Field, Hit, Interleave, Ray};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: batch_choice FIELD RAYS...";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else { return Err(usage.into()) };
    if args.len() < 2 {
        return Err(usage.into());
    }
    let field = Field::open(path)?;
    let view = field.view();
    let mut any = vec![false; 1024];
    let mut closest: Vec<Option<Hit>> = vec![None; 1024];
    for set in &args[1..] {
        let bytes = std::fs::read(set)?;
        let rays = match Ray::from_records(&bytes) {
            Some(rays) if !rays.is_empty() => rays,
            _ => return Err(format!("{set}: {} bytes, not a whole number of 32-byte rays", bytes.len()).into()),
        };
        let shadow = set.contains("shadow");
        let mut line = format!("{set:40} {:>7} rays", rays.len());
        for (name, how) in
            [("in turn", Interleave::Never), ("auto", Interleave::Auto), ("interleaved", Interleave::Always)]
        {
            let mut ns = vec![];
            for _ in 0..5 {
                let start = Instant::now();
                for chunk in rays.chunks(1024) {
                    let n = chunk.len();
                    if shadow {
                        view.any_hits_in(chunk, &mut any[..n], how);
                    } else {
                        view.closest_hits_in(chunk, &mut closest[..n], how);
                    }
                }
                ns.push(start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64);
            }
            ns.sort_by(f64::total_cmp);
            line += &format!("   {name} {:7.1} ns", ns[2]);
        }
        println!("{line}");
    }
    Ok(())
}
