//! The core-speed probe (`vlf_bench::latency::core_probe_ns`) beside the field and Embree, in
//! turn, again and again: whether the probe sees the machine's slow spells that the two see.
//!
//! ```text
//! cargo run --release -p vlf-bench --features embree --example core_probe -- FIELD RAYS SAMPLES
//! ```
//!
//! Prints, per sample, the probe's nanoseconds per step and each contestant's nanoseconds per ray
//! on `RAYS` (closest hit, one ray per call).

use std::time::Instant;
use vlf_bench::peers::contestant::Contestant;
use vlf_bench::peers::embree::EmbreeContestant;
use vlf_geom::Ray;
use vlf_runtime::Field;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: core_probe FIELD RAYS SAMPLES";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(path), Some(rays), Some(samples)) = (args.first(), args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let field = Field::open(path)?;
    let embree = EmbreeContestant::over_field(&field).map_err(|e| e.to_string())?;
    let bytes = std::fs::read(rays)?;
    let rays = Ray::from_records(&bytes).ok_or("RAYS: not a whole number of 32-byte rays")?;
    for _ in 0..samples.parse::<usize>()? {
        let probe = vlf_bench::latency::core_probe_ns();
        let start = Instant::now();
        let f = rays.iter().filter(|r| field.closest_hit(r).is_some()).count();
        let field_ns = start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64;
        let start = Instant::now();
        let e = rays.iter().filter(|r| embree.closest_hit(r).is_some()).count();
        let embree_ns = start.elapsed().as_secs_f64() * 1e9 / rays.len() as f64;
        assert_eq!(f, e, "the field and Embree disagree on the hit count");
        println!(
            "probe {probe:6.2} ns/step  field {field_ns:7.1} ns  embree {embree_ns:7.1} ns  field/embree {:.2}",
            embree_ns / field_ns
        );
    }
    Ok(())
}
