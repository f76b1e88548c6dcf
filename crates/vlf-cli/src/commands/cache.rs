//! `vlf-bake cache`: list, verify or prune a bake cache directory.

use super::stdout_line;
use crate::args::{CacheAction, CacheArgs};
use crate::values::BadUsage;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use vlf_bake::cache::{CACHE_DIR_ENV, Cache};
use vlf_bake::params::{count, human_bytes};

/// `vlf-bake cache list|verify|prune`.
pub fn run(a: &CacheArgs) -> Result<()> {
    let env = std::env::var_os(CACHE_DIR_ENV).filter(|v| !v.is_empty()).map(PathBuf::from);
    let Some(dir) = a.cache_dir.clone().or(env) else {
        return Err(BadUsage(format!("no cache directory: pass --cache-dir DIR or set {CACHE_DIR_ENV}")).into());
    };
    match std::fs::metadata(&dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => bail!("the cache directory {} is not a directory", dir.display()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            bail!("the cache directory {} does not exist", dir.display())
        }
        Err(e) => bail!("cannot read the cache directory {}: {e}", dir.display()),
    }
    let cache = Cache::open(&dir)?;
    match &a.action {
        CacheAction::List => {
            let entries = cache.list().with_context(|| format!("cannot list {}", dir.display()))?;
            if a.json {
                return stdout_line(&serde_json::to_string_pretty(&entries)?);
            }
            let total: u64 = entries.iter().map(|e| e.bytes).sum();
            let mut text = format!(
                "{}, {} in {}",
                count(entries.len() as u64, "entry", "entries"),
                human_bytes(total),
                dir.display()
            );
            for e in &entries {
                let what = match (&e.field, &e.problem) {
                    (Some(f), _) => format!(
                        "{}, {} directions × {}² tiles, format {}, from {}",
                        count(f.triangles, "triangle", "triangles"),
                        f.directions,
                        f.tile_resolution,
                        f.format_version,
                        f.inputs.join(", ")
                    ),
                    (None, problem) => format!("unusable: {}", problem.as_deref().unwrap_or("unknown")),
                };
                text.push_str(&format!(
                    "\n  {}  {:>10}  used {} ago  {what}",
                    &e.key[..16],
                    human_bytes(e.bytes),
                    human_duration(e.age_seconds)
                ));
            }
            stdout_line(&text)
        }
        CacheAction::Verify => {
            let outcomes = cache.verify(&mut |_| {}).with_context(|| format!("cannot verify {}", dir.display()))?;
            let bad: Vec<_> = outcomes.iter().filter(|o| o.problem.is_some()).collect();
            if a.json {
                stdout_line(&serde_json::to_string_pretty(&outcomes)?)?;
            } else {
                let mut text = format!("{} entries verified, {} bad", outcomes.len(), bad.len());
                for o in &bad {
                    text.push_str(&format!("\n  {} removed: {}", o.key, o.problem.as_deref().unwrap_or_default()));
                }
                stdout_line(&text)?;
            }
            if !bad.is_empty() {
                bail!("{} of {} cache entries failed verification and were removed", bad.len(), outcomes.len());
            }
            Ok(())
        }
        CacheAction::Prune { max_size, max_age } => {
            // (clap requires one of them: the `limit` group of `CacheAction::Prune`.)
            let r = cache.prune(*max_size, *max_age).with_context(|| format!("cannot prune {}", dir.display()))?;
            if a.json {
                return stdout_line(&serde_json::to_string_pretty(&r)?);
            }
            stdout_line(&format!(
                "removed {} entries ({}) and {} stale temporary files; kept {} entries ({})",
                r.removed.len(),
                human_bytes(r.removed_bytes),
                r.stale_temp_files,
                r.kept,
                human_bytes(r.kept_bytes)
            ))
        }
    }
}

/// `3 d`, `5 h`, `12 min`, `40 s`.
fn human_duration(seconds: f64) -> String {
    match seconds {
        s if s >= 86400.0 => format!("{:.0} d", s / 86400.0),
        s if s >= 3600.0 => format!("{:.0} h", s / 3600.0),
        s if s >= 60.0 => format!("{:.0} min", s / 60.0),
        s => format!("{s:.0} s"),
    }
}
