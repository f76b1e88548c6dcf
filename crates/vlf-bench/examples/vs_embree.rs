//! The single-ray field against Embree on ray files, in one process, the two timed in turn:
//! a quick check of a change to the query path between two runs of the peers benchmark.
//!
//! ```text
//! cargo run --release -p vlf-bench --features embree --example vs_embree -- FIELD ROUNDS RAYS...
//! ```
//!
//! Embree is built over the field's own triangles (its stored vertices plus its origin, in f32).
//! Each `RAYS` file (32-byte records, `formats/rays.md`) is traced `ROUNDS` times by each, one ray
//! per call (a file whose name contains `shadow` asks any hit, the others the closest hit); the
//! program prints the median nanoseconds per ray of each and their ratio (Embree's time over the
//! field's: above 1, the field is faster).

use std::time::Instant;
use vlf_bench::peers::contestant::Contestant;
use vlf_bench::peers::embree::EmbreeContestant;
use vlf_geom::Ray;
use vlf_runtime::Field;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: vs_embree FIELD ROUNDS RAYS...";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(path), Some(rounds)) = (args.first(), args.get(1)) else { return Err(usage.into()) };
    let field = Field::open(path)?;
    let rounds: usize = rounds.parse()?;
    if rounds == 0 {
        return Err("ROUNDS must be at least 1".into());
    }
    let embree = EmbreeContestant::over_field(&field).map_err(|e| e.to_string())?;
    for set in &args[2..] {
        let bytes = std::fs::read(set)?;
        let rays = match Ray::from_records(&bytes) {
            Some(rays) if !rays.is_empty() => rays,
            _ => return Err(format!("{set}: {} bytes, not a whole number of 32-byte rays", bytes.len()).into()),
        };
        let any = set.contains("shadow");
        let (mut field_ns, mut embree_ns) = (vec![], vec![]);
        let (mut field_hits, mut embree_hits) = (0, 0);
        for _ in 0..rounds {
            let start = Instant::now();
            field_hits =
                rays.iter().filter(|r| if any { field.any_hit(r) } else { field.closest_hit(r).is_some() }).count();
            field_ns.push(start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64);
            let start = Instant::now();
            embree_hits =
                rays.iter().filter(|r| if any { embree.any_hit(r) } else { embree.closest_hit(r).is_some() }).count();
            embree_ns.push(start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64);
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (f, e) = (median(&mut field_ns), median(&mut embree_ns));
        let name = std::path::Path::new(set).file_name().map_or(set.clone(), |n| n.to_string_lossy().into_owned());
        println!(
            "{name:32} {:7} rays, hits {field_hits}/{embree_hits}: field {f:7.1} ns, embree {e:7.1} ns, field/embree {:.2}",
            rays.len(),
            e / f
        );
    }
    Ok(())
}
