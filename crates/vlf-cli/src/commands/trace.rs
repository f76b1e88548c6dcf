//! `vlf-bake trace`: trace a file of rays against a field, write one hit record per ray.

use super::stdout_line;
use crate::args::TraceArgs;
use crate::distinct::{Writes, check_outputs};
use crate::limits::{check_disk, check_memory};
use crate::values::BadUsage;
use anyhow::{Context, Result, bail};
use std::io::Write;
use std::path::Path;
use std::time::Instant;
use vlf_bake::atomic::write_atomically;
use vlf_runtime::{Field, Hit, Ray};

/// Reads a rays file (`formats/rays.md`): 32-byte records. Only a regular file: a device such as
/// `/dev/zero` would be read without end, and a pipe waited on.
fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let bytes = vlf_bake::import::read_regular_file(path, u64::MAX)
        .with_context(|| format!("cannot read rays file {}", path.display()))?;
    match Ray::from_records(&bytes) {
        Some(rays) => Ok(rays),
        None => bail!(
            "rays file {} is {} bytes, not a multiple of the 32-byte ray record (formats/rays.md)",
            path.display(),
            bytes.len()
        ),
    }
}

/// Bytes of a rays file's record (`formats/rays.md`) and of a hits file's.
const RAY_BYTES: u64 = 32;
const HIT_BYTES: u64 = 16;

/// The most bytes of memory `trace` holds per ray: the file's records and the rays parsed from
/// them while it is read (32 each), then the rays, their hits (16) and instance ids (4).
const MEMORY_PER_RAY: u64 = 2 * RAY_BYTES;

/// Refuses, before anything is read or traced, a rays file whose rays this machine cannot hold
/// in memory, and outputs the file system has no room for: their sizes follow from the rays
/// file's. (A rays file that cannot be read is left for `read_rays` to report.)
fn check_room(a: &TraceArgs) -> Result<()> {
    let Ok(meta) = std::fs::metadata(&a.rays) else { return Ok(()) };
    if !meta.is_file() {
        return Ok(());
    }
    let n = meta.len() / RAY_BYTES;
    check_memory(
        n.saturating_mul(MEMORY_PER_RAY),
        &format!("tracing the {n} rays of {} ({MEMORY_PER_RAY} bytes a ray)", a.rays.display()),
    )?;
    check_disk(&a.output, n * HIT_BYTES, false, &format!("the hits file {} of {n} rays", a.output.display()))?;
    if let Some(ids) = &a.instance_ids {
        check_disk(ids, n * 4, false, &format!("the instance ids file {} of {n} rays", ids.display()))?;
    }
    Ok(())
}

/// The hits of `rays` in `field`, and the seconds spent tracing.
fn trace_field(a: &TraceArgs, field: &Field, rays: &[Ray]) -> (Vec<Hit>, f64) {
    let mut hits = vec![Hit::MISS; rays.len()];
    let start = Instant::now();
    if a.any_hit {
        use rayon::prelude::*;
        let view = field.view();
        rays.par_iter().zip(hits.par_iter_mut()).with_min_len(256).for_each(|(r, h)| {
            *h = Hit::record(view.any_hit_counted(r, &mut ()));
        });
    } else {
        field.par_closest_hits(rays, &mut hits);
    }
    (hits, start.elapsed().as_secs_f64())
}

/// `vlf-bake trace`: answers every ray of a rays file and writes the hits file.
pub fn run(a: &TraceArgs) -> Result<()> {
    // (clap does not enforce `requires` against an argument that conflicts with one present.)
    if a.instance_ids.is_some() && a.scene.is_none() {
        return Err(BadUsage("--instance-ids needs --scene: a field's hits name no instance".into()).into());
    }
    let source = a.field.as_deref().map(|f| ("FIELD", f)).or(a.scene.as_deref().map(|s| ("--scene", s)));
    let ids = a.instance_ids.as_deref().map(|i| ("--instance-ids", i));
    check_outputs(
        &[source.as_slice(), &[("--rays", a.rays.as_path())]].concat(),
        &[[("-o/--output", a.output.as_path())].as_slice(), ids.as_slice()].concat(),
        Writes::Through,
    )?;
    check_room(a)?;
    let rays;
    let (hits, seconds) = match (&a.field, &a.scene) {
        (_, Some(scene)) => {
            rays = read_rays(&a.rays)?;
            super::scene::trace(a, scene, &rays)?
        }
        (Some(path), None) => {
            let field = super::open_field(path)?;
            rays = read_rays(&a.rays)?;
            trace_field(a, &field, &rays)
        }
        (None, None) => unreachable!("clap requires a field or --scene"),
    };
    write_atomically(&a.output, |w| w.write_all(bytemuck::cast_slice(&hits)))
        .with_context(|| format!("cannot write hits file {}", a.output.display()))?;
    let hit_count = hits.iter().filter(|h| h.prim != u32::MAX).count();
    let invalid = rays.iter().filter(|r| !r.is_valid()).count();
    let mrays = rays.len() as f64 / seconds.max(1e-12) / 1e6;
    if a.json {
        stdout_line(
            &serde_json::json!({
                "rays": rays.len(), "hits": hit_count, "invalid": invalid,
                "seconds": seconds, "mrays_per_s": mrays,
                "threads": rayon::current_num_threads(), "any_hit": a.any_hit,
            })
            .to_string(),
        )
    } else if a.quiet {
        Ok(())
    } else {
        stdout_line(&format!(
            "traced {} rays ({} hits, {invalid} invalid) in {seconds:.3} s: {mrays:.2} Mrays/s on {} threads",
            rays.len(),
            hit_count,
            rayon::current_num_threads()
        ))
    }
}
