//! `bake` and `merge` as the command line runs them: import, prepare, look the inputs up in the
//! cache, choose parameters, bake a field or a shard, store the field in the cache; or check and
//! merge shards and store the result. Each phase is timed for the report ([`crate::report`]).

use crate::atomic::AtomicFile;
use crate::cache::{Cache, CacheKey, Lookup, key_for_scene, key_of_field};
use crate::error::BakeError;
use crate::params::{BakeConfig, Choice, choose};
use crate::prepare::Prepared;
use crate::progress::Progress;
use crate::report::{CacheReport, InputFile, OutputInfo, Parameters, Phases, Report, ShardInfo};
use crate::scene::{ImportError, ImportReport};
use crate::sections::params_record;
use crate::shard::{MergeSummary, ShardError, ShardSpec, merge};
use crate::statistics::Statistics;
use crate::writer::{BakeSummary, write_into};
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_format::hex;

/// Why a bake or merge failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum JobError {
    #[error(transparent)]
    Import(#[from] ImportError),
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    Shard(#[from] ShardError),
    #[error("cannot write {path}: {error}")]
    Io { path: PathBuf, error: std::io::Error },
}

/// A bake to run.
pub struct BakeJob<'a> {
    pub inputs: &'a [PathBuf],
    pub output: &'a Path,
    pub config: BakeConfig,
    pub shard: Option<ShardSpec>,
    /// `None`: no cache (the report says why, from `cache_note`).
    pub cache: Option<Cache>,
    pub cache_note: Option<String>,
    /// Called with the chosen parameters before the directions are baked (not on a cache hit).
    pub on_choice: Option<&'a dyn Fn(&Choice)>,
}

/// What a bake did.
pub struct BakeOutcome {
    pub summary: BakeSummary,
    pub import: ImportReport,
    /// `Some` on a cache hit: the entry the field was copied from.
    pub cache_hit: Option<PathBuf>,
    /// Set for a shard: its directions `first .. end`.
    pub shard: Option<ShardInfo>,
    pub report: Report,
    /// Problems that did not stop the bake (a corrupt cache entry, a failed store), one line each.
    pub warnings: Vec<String>,
}

/// Runs a whole bake job (see the module documentation): import, the cache, the bake of a field
/// or shard, and the report.
pub fn run_bake_job(job: &BakeJob<'_>, progress: &dyn Progress) -> Result<BakeOutcome, JobError> {
    let started = Instant::now();
    let phases = Phases::new(progress);
    let output = job.output;
    let io_err = |error| JobError::Io { path: output.to_path_buf(), error };
    let scene = phases.time("import", || crate::import::import_paths(job.inputs))?;
    let prep = phases.time("prepare", || Prepared::new(&scene));
    let request = job.config.request();
    let inputs = job
        .inputs
        .iter()
        .zip(&scene.inputs)
        .map(|(path, record)| InputFile {
            path: path.clone(),
            bytes: std::fs::metadata(path).map_or(0, |m| m.len()),
            blake3: Some(hex(&record.file_hash)),
            content_hash: None,
            shard: None,
        })
        .collect();
    let mut warnings = Vec::new();

    // Shards neither read nor fill the cache: only whole fields are cached.
    let cache = job.cache.as_ref().filter(|_| job.shard.is_none());
    let key: Option<CacheKey> = cache.map(|_| phases.time("cache_key", || key_for_scene(&prep, &request)));
    let mut cache_report = match (cache, job.shard) {
        (Some(c), _) => CacheReport {
            status: "miss",
            dir: Some(c.root().to_path_buf()),
            key: key.map(|k| k.to_string()),
            stored: false,
            note: None,
        },
        (None, Some(_)) if job.cache.is_some() => CacheReport::disabled(Some(
            "shard bakes do not use the cache; `vlf-bake merge --cache-dir` stores the merged field".into(),
        )),
        (None, _) => CacheReport::disabled(job.cache_note.clone()),
    };

    if let (Some(cache), Some(key)) = (cache, key) {
        match phases.time("cache_lookup", || cache.lookup(&key, output)).map_err(io_err)? {
            Lookup::Hit(hit) => {
                cache_report.status = "hit";
                let p = &hit.params;
                let summary = BakeSummary {
                    output: output.to_path_buf(),
                    triangles: hit.triangles,
                    dropped_degenerate: hit.dropped_degenerate,
                    dropped_precision: hit.dropped_precision,
                    dropped_duplicates: hit.dropped_duplicates,
                    directions: p.direction_count,
                    lattice_n: p.lattice_n,
                    tile_resolution: p.tile_resolution,
                    leaf_size: p.leaf_size,
                    max_depth: p.max_depth,
                    automatic: p.is_automatic(),
                    choice: format!("copied from the cache entry {}", cache.entry_path(&key).display()),
                    estimated_bytes: None,
                    bytes: hit.header.file_length,
                    seconds: started.elapsed().as_secs_f64(),
                    content_hash: hex(&hit.header.content_hash),
                    input_hash: hex(&hit.header.input_hash),
                    statistics: Statistics::from_record(&hit.statistics),
                };
                let report = Report::new(
                    "bake",
                    rayon::current_num_threads(),
                    inputs,
                    Parameters::from_record(p, "cache", None),
                    None,
                    cache_report,
                    output_info(output, "field", &hit.header),
                    phases.list(),
                    started.elapsed().as_secs_f64(),
                );
                return Ok(BakeOutcome {
                    summary,
                    import: scene.report.clone(),
                    cache_hit: Some(cache.entry_path(&key)),
                    shard: None,
                    report,
                    warnings,
                });
            }
            Lookup::Miss => {}
            Lookup::Unusable { problem } => {
                cache_report.note = Some(problem.clone());
                warnings.push(problem);
            }
        }
    }

    let choice = phases.time("choose", || choose(&prep, &job.config))?;
    if let Some(announce) = job.on_choice {
        announce(&choice);
    }
    let tmp = AtomicFile::create(output).map_err(io_err)?;
    let baked = write_into(&prep, &choice, &request, tmp.file(), output, job.shard, &phases)?;
    let written = tmp.file().try_clone().map_err(io_err)?;
    tmp.commit().map_err(io_err)?;
    phases.end();

    if let (Some(cache), Some(key)) = (cache, key) {
        match phases.time("cache_store", || cache.store(&key, &written)) {
            Ok(()) => cache_report.stored = true,
            Err(e) => {
                let problem = format!("cannot store the field in the cache {}: {e}", cache.root().display());
                cache_report.note = Some(problem.clone());
                warnings.push(problem);
            }
        }
    }

    let shard = job.shard.map(|s| ShardInfo {
        index: s.index,
        count: s.count,
        first_direction: baked.directions.start,
        end_direction: baked.directions.end,
        direction_count: baked.direction_count,
    });
    let estimated = choice.estimated_bytes;
    let source = if choice.automatic { "automatic" } else { "requested" };
    let report = Report::new(
        "bake",
        rayon::current_num_threads(),
        inputs,
        Parameters::from_record(&params_record(&choice.params, &request), source, estimated),
        shard.clone(),
        cache_report,
        output_info(output, if job.shard.is_some() { "shard" } else { "field" }, &baked.header),
        phases.list(),
        started.elapsed().as_secs_f64(),
    );
    Ok(BakeOutcome {
        summary: baked.summary(&prep, &choice, output, started.elapsed().as_secs_f64()),
        import: scene.report.clone(),
        cache_hit: None,
        shard,
        report,
        warnings,
    })
}

fn output_info(path: &Path, kind: &'static str, header: &vlf_format::Header) -> OutputInfo {
    OutputInfo {
        path: path.to_path_buf(),
        kind,
        bytes: header.file_length,
        content_hash: hex(&header.content_hash),
        input_hash: hex(&header.input_hash),
    }
}

/// What a merge did.
pub struct MergeOutcome {
    pub summary: MergeSummary,
    pub report: Report,
    pub warnings: Vec<String>,
}

/// Runs a whole merge job: checks and merges `parts` into `output`; with a cache, stores the
/// merged field in it; and the report.
pub fn run_merge_job(
    parts: &[PathBuf],
    output: &Path,
    cache: Option<Cache>,
    cache_note: Option<String>,
    progress: &dyn Progress,
) -> Result<MergeOutcome, JobError> {
    let started = Instant::now();
    let phases = Phases::new(progress);
    let summary = merge(parts, output, &phases)?;
    let mut timed = vec![crate::report::Phase { name: "check".into(), seconds: summary.check_seconds }];
    let mut warnings = Vec::new();
    let mut cache_report = CacheReport::disabled(cache_note);
    if let Some(cache) = &cache {
        let stored = phases.time("cache_store", || -> Result<CacheKey, String> {
            let field = vlf_runtime::Field::open(output).map_err(|e| e.to_string())?;
            let key = key_of_field(field.reader().header, field.reader().table);
            let file = std::fs::File::open(output).map_err(|e| e.to_string())?;
            cache.store(&key, &file).map_err(|e| e.to_string())?;
            Ok(key)
        });
        cache_report = CacheReport {
            status: "store",
            dir: Some(cache.root().to_path_buf()),
            key: stored.as_ref().ok().map(|k| k.to_string()),
            stored: stored.is_ok(),
            note: None,
        };
        if let Err(e) = stored {
            let problem = format!("cannot store the merged field in the cache {}: {e}", cache.root().display());
            cache_report.note = Some(problem.clone());
            warnings.push(problem);
        }
    }
    timed.extend(phases.list());
    let inputs = summary
        .parts
        .iter()
        .map(|p| InputFile {
            path: p.path.clone(),
            bytes: p.bytes,
            blake3: None,
            content_hash: Some(p.content_hash.clone()),
            shard: Some(p.shard.clone()),
        })
        .collect();
    let report = Report::new(
        "merge",
        1,
        inputs,
        Parameters::from_record(&summary.params, "shards", None),
        None,
        cache_report,
        output_info(output, "field", &summary.header),
        timed,
        started.elapsed().as_secs_f64(),
    );
    Ok(MergeOutcome { summary, report, warnings })
}
