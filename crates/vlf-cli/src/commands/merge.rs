//! `vlf-bake merge`: check the shards of a bake and merge them into its field; print the summary.

use super::{resolve_cache, stdout_line};
use crate::args::MergeArgs;
use crate::distinct::{Writes, check_outputs};
use crate::progress::Bar;
use anyhow::{Context, Result};
use vlf_bake::job::run_merge_job;
use vlf_bake::params::human_bytes;

/// `vlf-bake merge`: runs the merge job and prints its summary.
pub fn run(a: &MergeArgs) -> Result<()> {
    let parts: Vec<_> = a.parts.iter().map(|p| ("SHARD", p.as_path())).collect();
    let report = a.report.as_deref().map(|r| ("--report", r));
    check_outputs(
        &parts,
        &[[("-o/--output", a.output.as_path())].as_slice(), report.as_slice()].concat(),
        Writes::Files,
    )?;
    let (cache, cache_note) = resolve_cache(&a.cache);
    let bar = Bar::new(a.quiet || a.json);
    let out = run_merge_job(&a.parts, &a.output, cache, cache_note, &bar)?;
    // Warnings print whatever --quiet says: it hides the progress bar and the summary only.
    for w in &out.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(path) = &a.report {
        // Checked up front (`check_outputs`), so only a failing disk gets here: the merge is done.
        out.report.write(path).with_context(|| {
            format!("the field {} was written, but cannot write the report {}", a.output.display(), path.display())
        })?;
    }
    let s = &out.summary;
    if a.json {
        stdout_line(&serde_json::to_string(s)?)?;
    } else if !a.quiet {
        stdout_line(&format!(
            "merged {} shards into {}: {} directions × {}² tiles, {} ({} bytes) in {:.2} s\n  content hash {}\n  input hash   {}",
            s.shards,
            s.output.display(),
            s.directions,
            s.tile_resolution,
            human_bytes(s.bytes),
            s.bytes,
            s.check_seconds + s.copy_seconds,
            s.content_hash,
            s.input_hash
        ))?;
    }
    Ok(())
}
