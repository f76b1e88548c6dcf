//! The machine-readable report of `vlf-bake bake` and `vlf-bake merge` (`--report FILE.json`):
//! what a CI job uploads next to the field. The schema is versioned ([`SCHEMA`]) and documented in
//! `docs/build-farms.md`; fields are only ever added within a schema version.

use crate::progress::Progress;
use crate::sections::BAKER_REVISION;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;
use vlf_format::{ParamsRecord, VERSION_MAJOR, VERSION_MINOR};

/// The report's schema identifier.
pub const SCHEMA: &str = "vlf-bake-report/1";

/// The report. See `docs/build-farms.md` for every key.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub schema: &'static str,
    /// `bake` or `merge`.
    pub command: &'static str,
    pub vlf_bake_version: &'static str,
    /// The format version the command writes, `major.minor`.
    pub format_version: String,
    pub baker_revision: u32,
    /// Worker threads of the bake (1 for a merge, which streams on one thread).
    pub threads: usize,
    /// Mesh files for `bake`, shard files for `merge`, in command-line order.
    pub inputs: Vec<InputFile>,
    pub parameters: Parameters,
    /// The shard a `bake --shard` wrote; `null` otherwise.
    pub shard: Option<ShardInfo>,
    pub cache: CacheReport,
    pub output: OutputInfo,
    /// Wall-clock seconds of each phase, in order.
    pub phases: Vec<Phase>,
    /// Wall-clock seconds of the whole command.
    pub seconds: f64,
    pub peak_memory: PeakMemory,
}

/// One input file.
#[derive(Clone, Debug, Serialize)]
pub struct InputFile {
    pub path: PathBuf,
    pub bytes: u64,
    /// BLAKE3 of the file's bytes (mesh inputs; the hash the field's INPUTS section records).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blake3: Option<String>,
    /// The shard's content hash, which commits to every byte of it (shard inputs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub content_hash: Option<String>,
    /// `K/N` (shard inputs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
}

/// The parameters as requested and as chosen (PARAMS, `formats/vlf.md` §5.2).
#[derive(Clone, Debug, Serialize)]
pub struct Parameters {
    pub requested: Requested,
    pub chosen: Chosen,
}

#[derive(Clone, Debug, Serialize)]
pub struct Requested {
    /// `null`: automatic.
    pub directions: Option<u32>,
    /// `null`: automatic.
    pub tiles: Option<u32>,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub max_bytes: u64,
    pub max_bytes_per_triangle: u64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Chosen {
    pub directions: u32,
    pub lattice_n: u32,
    pub tiles: u32,
    pub leaf_size: u32,
    pub max_depth: u32,
    pub margin: f64,
    /// How they were found: `requested`, `automatic` (the size-budget search), `cache` (read
    /// from the cached field) or `shards` (read from the merged shards).
    pub source: &'static str,
    /// The automatic search's size estimate.
    pub estimated_bytes: Option<u64>,
}

impl Parameters {
    /// From a PARAMS record, which holds both the request and the choice.
    pub fn from_record(p: &ParamsRecord, source: &'static str, estimated_bytes: Option<u64>) -> Self {
        Parameters {
            requested: Requested {
                directions: p.requested_directions(),
                tiles: p.requested_tiles(),
                leaf_size: p.leaf_size,
                max_depth: p.max_depth,
                max_bytes: p.max_bytes,
                max_bytes_per_triangle: p.max_bytes_per_triangle,
            },
            chosen: Chosen {
                directions: p.direction_count,
                lattice_n: p.lattice_n,
                tiles: p.tile_resolution,
                leaf_size: p.leaf_size,
                max_depth: p.max_depth,
                margin: p.margin,
                source,
                estimated_bytes,
            },
        }
    }
}

/// The shard a bake wrote.
#[derive(Clone, Debug, Serialize)]
pub struct ShardInfo {
    pub index: u32,
    pub count: u32,
    /// Its directions `first_direction .. end_direction` of `direction_count`.
    pub first_direction: u32,
    pub end_direction: u32,
    pub direction_count: u32,
}

/// What the cache did.
#[derive(Clone, Debug, Serialize)]
pub struct CacheReport {
    /// `bake`: `hit`, `miss` or `disabled`; `merge` (which never looks up): `store` or `disabled`.
    pub status: &'static str,
    pub dir: Option<PathBuf>,
    /// The cache key (`docs/build-farms.md`), when a cache was given.
    pub key: Option<String>,
    /// Whether the output was stored in the cache.
    pub stored: bool,
    /// Why the cache was not used, or what went wrong with it (never fatal).
    pub note: Option<String>,
}

impl CacheReport {
    pub fn disabled(note: Option<String>) -> Self {
        CacheReport { status: "disabled", dir: None, key: None, stored: false, note }
    }
}

/// The file written.
#[derive(Clone, Debug, Serialize)]
pub struct OutputInfo {
    pub path: PathBuf,
    /// `field` or `shard`.
    pub kind: &'static str,
    pub bytes: u64,
    /// The header's content hash, which commits to every byte of the file (`formats/vlf.md` §3.1).
    pub content_hash: String,
    pub input_hash: String,
}

/// One timed phase.
#[derive(Clone, Debug, Serialize)]
pub struct Phase {
    pub name: String,
    pub seconds: f64,
}

/// The peak resident memory of the process.
#[derive(Clone, Debug, Serialize)]
pub struct PeakMemory {
    /// `null` where the system does not say.
    pub bytes: Option<u64>,
    pub source: &'static str,
}

impl PeakMemory {
    /// The high-water mark of the resident set (`VmHWM` in `/proc/self/status`, Linux); absent
    /// elsewhere.
    pub fn now() -> Self {
        let bytes = std::fs::read_to_string("/proc/self/status").ok().and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
            let kib: u64 = line["VmHWM:".len()..].trim().strip_suffix("kB")?.trim().parse().ok()?;
            Some(kib * 1024)
        });
        let source = if bytes.is_some() { "VmHWM in /proc/self/status" } else { "unavailable on this system" };
        PeakMemory { bytes, source }
    }
}

impl Report {
    /// A report with the common fields filled in.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        command: &'static str,
        threads: usize,
        inputs: Vec<InputFile>,
        parameters: Parameters,
        shard: Option<ShardInfo>,
        cache: CacheReport,
        output: OutputInfo,
        phases: Vec<Phase>,
        seconds: f64,
    ) -> Self {
        Report {
            schema: SCHEMA,
            command,
            vlf_bake_version: env!("CARGO_PKG_VERSION"),
            format_version: format!("{VERSION_MAJOR}.{VERSION_MINOR}"),
            baker_revision: BAKER_REVISION,
            threads,
            inputs,
            parameters,
            shard,
            cache,
            output,
            phases,
            seconds,
            peak_memory: PeakMemory::now(),
        }
    }

    /// Writes the report as pretty JSON to `path`, atomically.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        crate::atomic::write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self)?;
            std::io::Write::write_all(w, b"\n")
        })
    }
}

/// Times phases: explicitly with [`Phases::time`], and the bake's own phases by standing in for
/// its [`Progress`] (forwarding every call to the real one).
pub struct Phases<'a> {
    inner: &'a dyn Progress,
    open: Mutex<Option<(String, Instant)>>,
    done: Mutex<Vec<Phase>>,
}

/// The report's name of a progress phase.
fn phase_name(progress_phase: &str) -> &str {
    match progress_phase {
        "baking directions" => "bake",
        "merging shards" => "copy",
        "writing" => "write",
        other => other,
    }
}

impl<'a> Phases<'a> {
    pub fn new(inner: &'a dyn Progress) -> Self {
        Phases { inner, open: Mutex::new(None), done: Mutex::new(Vec::new()) }
    }

    /// Runs `f` as the phase `name`.
    pub fn time<T>(&self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let value = f();
        self.push(name, start.elapsed().as_secs_f64());
        value
    }

    /// Records a phase timed elsewhere.
    pub fn push(&self, name: &str, seconds: f64) {
        self.done.lock().unwrap_or_else(|e| e.into_inner()).push(Phase { name: name.to_string(), seconds });
    }

    /// The phases recorded so far.
    pub fn list(&self) -> Vec<Phase> {
        self.done.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

impl Progress for Phases<'_> {
    fn begin(&self, phase: &str, total: u64) {
        self.inner.begin(phase, total);
        *self.open.lock().unwrap_or_else(|e| e.into_inner()) = Some((phase_name(phase).to_string(), Instant::now()));
    }

    fn advance(&self, done: u64) {
        self.inner.advance(done);
    }

    fn end(&self) {
        self.inner.end();
        if let Some((name, start)) = self.open.lock().unwrap_or_else(|e| e.into_inner()).take() {
            self.push(&name, start.elapsed().as_secs_f64());
        }
    }
}
