//! `vlf-bake bake`: import, bake (or bake one shard), through the cache; print the summary.

use super::{resolve_cache, stdout_line};
use crate::args::BakeArgs;
use crate::distinct::{Writes, check_outputs};
use crate::progress::Bar;
use anyhow::{Context, Result};
use vlf_bake::job::{BakeJob, run_bake_job};
use vlf_bake::params::{count, human_bytes};
use vlf_bake::{BakeConfig, DepthPolicy};

/// `vlf-bake bake`: runs the bake job and prints its summary.
pub fn run(a: &BakeArgs) -> Result<()> {
    let inputs: Vec<_> = a.inputs.iter().map(|i| ("INPUT", i.as_path())).collect();
    let report = a.report.as_deref().map(|r| ("--report", r));
    check_outputs(
        &inputs,
        &[[("-o/--output", a.output.as_path())].as_slice(), report.as_slice()].concat(),
        Writes::Files,
    )?;
    let config = BakeConfig {
        directions: a.directions,
        tiles: a.tiles,
        depth: DepthPolicy { leaf_size: a.leaf_size, max_depth: a.max_depth },
        max_bytes: a.max_bytes,
        max_bytes_per_triangle: a.max_bytes_per_triangle,
    };
    config.validate()?;
    let (cache, cache_note) = resolve_cache(&a.cache);
    let bar = Bar::new(a.quiet || a.json);
    let explain = |choice: &vlf_bake::Choice| {
        if choice.automatic {
            eprintln!("{}", choice.reason);
        }
    };
    let job = BakeJob {
        inputs: &a.inputs,
        output: &a.output,
        config,
        shard: a.shard,
        cache,
        cache_note,
        on_choice: (!a.quiet && !a.json).then_some(&explain as &dyn Fn(&vlf_bake::Choice)),
    };
    let out = run_bake_job(&job, &bar)?;
    // Warnings print whatever --quiet says: it hides the progress bar and the summary only.
    for w in out.import.warnings.iter().chain(&out.warnings) {
        eprintln!("warning: {w}");
    }
    if let Some(path) = &a.report {
        // Checked up front (`check_outputs`), so only a failing disk gets here: the bake is done.
        let what = if out.shard.is_some() { "shard" } else { "field" };
        out.report.write(path).with_context(|| {
            format!("the {what} {} was written, but cannot write the report {}", a.output.display(), path.display())
        })?;
    }
    let summary = &out.summary;
    if a.json {
        #[derive(serde::Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            summary: &'a vlf_bake::BakeSummary,
            import: &'a vlf_bake::ImportReport,
            cache: &'a str,
            #[serde(skip_serializing_if = "Option::is_none")]
            shard: Option<&'a vlf_bake::report::ShardInfo>,
        }
        let out = Out { summary, import: &out.import, cache: out.report.cache.status, shard: out.shard.as_ref() };
        stdout_line(&serde_json::to_string(&out)?)?;
    } else if !a.quiet {
        let s = summary;
        let what = match &out.shard {
            Some(sh) => format!(
                "shard {}/{} (directions {}..{} of {})",
                sh.index, sh.count, sh.first_direction, sh.end_direction, sh.direction_count
            ),
            None => format!("{} directions", s.directions),
        };
        let how = match &out.cache_hit {
            Some(entry) => format!("copied from the cache ({}) in {:.2} s", entry.display(), s.seconds),
            None => format!("in {:.2} s", s.seconds),
        };
        let mut text = format!(
            "baked {}: {}, {what} × {}² tiles, {} ({} bytes) {how}\n  content hash {}\n  input hash   {}",
            s.output.display(),
            count(s.triangles, "triangle", "triangles"),
            s.tile_resolution,
            human_bytes(s.bytes),
            s.bytes,
            s.content_hash,
            s.input_hash
        );
        let r = &out.import;
        if r.dropped_degenerate + r.skipped_points + r.skipped_lines > 0 {
            text.push_str(&format!(
                "\n  dropped {} degenerate triangles; skipped {} point and {} line primitives",
                r.dropped_degenerate, r.skipped_points, r.skipped_lines
            ));
        }
        stdout_line(&text)?;
    }
    Ok(())
}
