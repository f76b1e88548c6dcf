//! The bake cache (`vlf-bake bake --cache-dir DIR`, `VLF_CACHE_DIR`): finished fields stored
//! under a key computed from the inputs, so that a bake of unchanged inputs costs an import, a
//! few hashes and a copy.
//!
//! **Key.** BLAKE3 of `"VLF-CACHE-KEY\0"`, the field's input hash (`formats/vlf.md` §3.2: format
//! major, baker revision, request, canonical triangles and provenance), the format's major and
//! minor version, and, for every shared section that depends on the scene alone (every section
//! except the parameter sections [`PARAMETER_KINDS`] and the per-direction ones) in increasing
//! kind order, its kind, element size, length and BLAKE3. The input hash alone would miss the
//! format minor and SCENE's count of dropped triangles; the section list also takes in any section
//! a later format adds (materials, cameras) without a change here. The parameters are not in the
//! key: they are chosen deterministically from the inputs and the request, which are. The key is
//! computed before the bake from the imported scene ([`key_for_scene`]), and from any field's
//! header and table ([`key_of_field`]), which is how `merge` stores what a farm baked and how
//! `cache verify` checks that an entry sits under the right name.
//!
//! **Layout.** `DIR/v1/<key as 64 hex digits>.vlf`, nothing else: the entry is the field itself,
//! which already says what it is. Entries are written to a temporary file in the same directory
//! and renamed into place, so concurrent bakes of the same inputs both succeed (the last rename
//! wins; the bytes are the same) and a reader never sees a partial entry. The modification time
//! is touched on every hit: pruning by size removes the least recently used entries first.
//!
//! **Hits.** The entry is copied into a temporary file beside the output (in whole 2 MiB writes,
//! as a bake writes), the copy is opened as a field (header, table and content hash) and its key
//! recomputed, every section's bytes are hashed against the table (`vlf_format::verify_hashes`:
//! time linear in the size, as the copy's is), and only then is it renamed over the output. A
//! copy rather than a hard link: the output is the user's to modify, chmod or truncate in place,
//! and none of that may reach the cache. An entry that fails the checks is removed and the bake
//! proceeds. `vlf-bake cache verify` checks more: every offset and index, as `dump --verify`.

use crate::atomic::{AtomicFile, remove_stale_temp_files};
use crate::inspect;
use crate::prepare::Prepared;
use crate::sections::{PARAMETER_KINDS, SharedSection, input_hash, scene_sections};
use std::fs::File;
use std::io::{self, Seek};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};
use vlf_format::shard::is_per_direction;
use vlf_format::{AlignedWriter, FieldReader, Header, Request, SectionEntry, VERSION_MAJOR, VERSION_MINOR, hex};
use vlf_runtime::Field;

/// The environment variable naming the cache directory when `--cache-dir` is absent.
pub const CACHE_DIR_ENV: &str = "VLF_CACHE_DIR";

/// Which cache a bake uses, as every front end resolves it: none when `no_cache`; else `dir`,
/// else `$VLF_CACHE_DIR` (ignored when empty). Gives the cache, or why none is used, naming the
/// front end's own options (`no_cache_option`, `dir_option`: `--no-cache` and `--cache-dir` for
/// the command line). A directory that cannot be opened is `Err` with the reason, for the front
/// end to warn about; the bake then goes on without a cache.
pub fn resolve(
    dir: Option<PathBuf>,
    no_cache: bool,
    no_cache_option: &str,
    dir_option: &str,
) -> Result<Result<Cache, String>, String> {
    if no_cache {
        return Err(no_cache_option.to_owned());
    }
    let env = std::env::var_os(CACHE_DIR_ENV).filter(|v| !v.is_empty()).map(PathBuf::from);
    match dir.or(env) {
        None => Err(format!("no {dir_option} and no {CACHE_DIR_ENV}")),
        Some(dir) => Ok(Cache::open(&dir).map_err(|e| format!("not using the cache: {e}"))),
    }
}
/// The subdirectory of this cache layout.
pub const LAYOUT: &str = "v1";

/// A cache key: 32 bytes, written as 64 lower-case hex digits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CacheKey(pub [u8; 32]);

impl std::fmt::Display for CacheKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&hex(&self.0))
    }
}

fn key_from(input_hash: &[u8; 32], major: u16, minor: u16, entries: &[SectionEntry]) -> CacheKey {
    let mut sections: Vec<&SectionEntry> = entries
        .iter()
        .filter(|e| !is_per_direction(e.kind) && !PARAMETER_KINDS.iter().any(|k| *k as u32 == e.kind))
        .collect();
    sections.sort_by_key(|e| e.kind);
    let mut h = blake3::Hasher::new();
    h.update(b"VLF-CACHE-KEY\0");
    h.update(input_hash);
    h.update(&major.to_le_bytes());
    h.update(&minor.to_le_bytes());
    for e in sections {
        h.update(&e.kind.to_le_bytes());
        h.update(&e.element_size.to_le_bytes());
        h.update(&e.raw_length.to_le_bytes());
        h.update(&e.raw_hash);
    }
    CacheKey(*h.finalize().as_bytes())
}

/// The key of the field a bake of `prep` with `request` writes, computed before baking.
pub fn key_for_scene(prep: &Prepared<'_>, request: &Request) -> CacheKey {
    let entries: Vec<SectionEntry> = scene_sections(prep).iter().map(SharedSection::entry).collect();
    key_from(&input_hash(prep.scene, request), VERSION_MAJOR, VERSION_MINOR, &entries)
}

/// The key of a field (or shard: its SHARD record is ignored) from its header and table.
pub fn key_of_field(header: &Header, table: &[SectionEntry]) -> CacheKey {
    let table: Vec<SectionEntry> = table.iter().filter(|e| e.kind != vlf_format::shard::SHARD_KIND).copied().collect();
    key_from(&header.input_hash, header.version_major, header.version_minor, &table)
}

/// A cache directory.
#[derive(Clone, Debug)]
pub struct Cache {
    root: PathBuf,
    dir: PathBuf,
}

/// What a lookup found.
pub enum Lookup {
    /// The entry was copied to the output.
    Hit(Box<CacheHit>),
    /// No entry under the key.
    Miss,
    /// An entry was there but could not be read, or failed the checks (and was removed). Bake
    /// as on a miss.
    Unusable { problem: String },
}

/// A materialised entry: what the field copied to the output says of itself.
pub struct CacheHit {
    pub header: Header,
    pub params: vlf_format::ParamsRecord,
    pub statistics: vlf_format::StatisticsRecord,
    pub triangles: u64,
    pub dropped_degenerate: u64,
    pub dropped_precision: u64,
    pub dropped_duplicates: u64,
}

/// One entry, as `cache list` shows it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct EntryInfo {
    pub key: String,
    pub path: PathBuf,
    pub bytes: u64,
    /// Seconds since the entry was stored or last hit.
    pub age_seconds: f64,
    /// What the field's header and small sections say, if they pass the open checks.
    #[serde(flatten)]
    pub field: Option<FieldInfo>,
    /// Why the entry cannot be opened as a field.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub problem: Option<String>,
}

/// The field behind an entry.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FieldInfo {
    pub format_version: String,
    pub input_hash: String,
    pub content_hash: String,
    pub triangles: u64,
    pub directions: u32,
    pub tile_resolution: u32,
    pub inputs: Vec<String>,
}

/// What `prune` removed and kept.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PruneReport {
    pub removed: Vec<String>,
    pub removed_bytes: u64,
    pub kept: usize,
    pub kept_bytes: u64,
    pub stale_temp_files: usize,
}

/// One entry's result in `cache verify`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VerifyOutcome {
    pub key: String,
    pub bytes: u64,
    /// `None` if the entry verified; otherwise the fault (the entry was removed).
    pub problem: Option<String>,
}

fn is_entry_name(name: &str) -> Option<&str> {
    let key = name.strip_suffix(".vlf")?;
    (key.len() == 64 && key.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))).then_some(key)
}

/// The same file (device and inode), so that a corrupt entry is removed only if it was not
/// replaced meanwhile.
#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino()
}

#[cfg(not(unix))]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    a.len() == b.len() && a.modified().ok() == b.modified().ok()
}

impl Cache {
    /// The cache in `root` (created if absent).
    pub fn open(root: &Path) -> io::Result<Cache> {
        let dir = root.join(LAYOUT);
        std::fs::create_dir_all(&dir).map_err(|e| {
            io::Error::new(e.kind(), format!("cannot create the cache directory {}: {e}", dir.display()))
        })?;
        Ok(Cache { root: root.to_path_buf(), dir })
    }

    /// The directory the user named.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Where the entry of `key` lives.
    pub fn entry_path(&self, key: &CacheKey) -> PathBuf {
        self.dir.join(format!("{key}.vlf"))
    }

    /// Looks `key` up and, on a hit, writes the field to `output` atomically (see the module
    /// documentation). I/O errors on the output are errors; a bad entry is [`Lookup::Unusable`].
    pub fn lookup(&self, key: &CacheKey, output: &Path) -> io::Result<Lookup> {
        let path = self.entry_path(key);
        let mut entry = match File::open(&path) {
            Ok(f) => f,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Lookup::Miss),
            Err(e) => {
                let problem = format!("cannot read cache entry {}: {e}", path.display());
                return Ok(Lookup::Unusable { problem });
            }
        };
        let tmp = AtomicFile::create(output)?;
        // Whole 2 MiB writes, so that the field maps with huge pages (`vlf_format::writer`).
        let mut w = AlignedWriter::new(tmp.file());
        io::copy(&mut entry, &mut w)?;
        w.finish()?;
        let checked = Field::open(tmp.temp_path()).map_err(|e| e.to_string()).and_then(|field| {
            let r = field.reader();
            let found = key_of_field(r.header, r.table);
            if found != *key {
                return Err(format!("it holds the field of key {found}"));
            }
            // Every byte, against the section hashes: the open above checked only the header
            // and table, and a byte flipped on disk inside a section would otherwise reach the
            // output. (A packed entry's hashes were checked as it was decoded.)
            if !field.is_packed() {
                vlf_format::verify_hashes(r, &mut |_, _| {}).map_err(|e| e.to_string())?;
            }
            Ok(CacheHit {
                header: *r.header,
                params: *r.params,
                statistics: *r.statistics,
                triangles: r.scene.triangle_count,
                dropped_degenerate: r.scene.dropped_degenerate,
                dropped_precision: r.scene.dropped_precision,
                dropped_duplicates: r.scene.dropped_duplicates,
            })
        });
        match checked {
            Ok(hit) => {
                tmp.commit()?;
                let hit = Box::new(hit);
                // Best effort: the time orders entries for pruning; a cache shared between users
                // may not let us set it.
                let _ = entry.set_modified(SystemTime::now());
                Ok(Lookup::Hit(hit))
            }
            Err(problem) => {
                drop(tmp);
                if let (Ok(opened), Ok(now)) = (entry.metadata(), std::fs::metadata(&path))
                    && same_file(&opened, &now)
                {
                    let _ = std::fs::remove_file(&path);
                }
                Ok(Lookup::Unusable {
                    problem: format!("cache entry {} is unusable and was removed: {problem}", path.display()),
                })
            }
        }
    }

    /// Stores the field in `field` (a file open for reading, any position) under `key`.
    pub fn store(&self, key: &CacheKey, field: &File) -> io::Result<()> {
        let path = self.entry_path(key);
        let mut src = field.try_clone()?;
        src.rewind()?;
        let tmp = AtomicFile::create(&path)?;
        // Whole 2 MiB writes, as a bake's own (`vlf_format::writer`).
        let mut w = AlignedWriter::new(tmp.file());
        io::copy(&mut src, &mut w)?;
        w.finish()?;
        tmp.commit()
    }

    /// Every entry, most recently used first.
    pub fn list(&self) -> io::Result<Vec<EntryInfo>> {
        let mut entries = Vec::new();
        let now = SystemTime::now();
        for item in std::fs::read_dir(&self.dir)? {
            let item = item?;
            let name = item.file_name();
            let Some(key) = name.to_str().and_then(is_entry_name) else { continue };
            let meta = match item.metadata() {
                Ok(m) => m,
                Err(e) if e.kind() == io::ErrorKind::NotFound => continue, // pruned meanwhile
                Err(e) => return Err(e),
            };
            let age = meta.modified().ok().and_then(|m| now.duration_since(m).ok()).unwrap_or_default();
            let path = item.path();
            let (field, problem) = match Field::open(&path) {
                Ok(f) => (Some(describe(f.reader())), None),
                Err(e) => (None, Some(e.to_string())),
            };
            entries.push(EntryInfo {
                key: key.to_string(),
                path,
                bytes: meta.len(),
                age_seconds: age.as_secs_f64(),
                field,
                problem,
            });
        }
        entries.sort_by(|a, b| a.age_seconds.total_cmp(&b.age_seconds).then_with(|| a.key.cmp(&b.key)));
        Ok(entries)
    }

    /// Verifies every entry completely (every hash, offset and index, as `dump --verify`, and the
    /// key against the name); removes the ones that fail.
    pub fn verify(&self, progress: &mut dyn FnMut(&EntryInfo)) -> io::Result<Vec<VerifyOutcome>> {
        let mut out = Vec::new();
        for info in self.list()? {
            progress(&info);
            let problem = match Field::open(&info.path) {
                Err(e) => Some(e.to_string()),
                Ok(field) => {
                    let r = field.reader();
                    match inspect::verify(r, &mut |_, _| {}) {
                        Err(e) => Some(e.to_string()),
                        Ok(_) if key_of_field(r.header, r.table).to_string() != info.key => {
                            Some(format!("it holds the field of key {}", key_of_field(r.header, r.table)))
                        }
                        Ok(_) => None,
                    }
                }
            };
            if problem.is_some() {
                remove_if_present(&info.path)?;
            }
            out.push(VerifyOutcome { key: info.key, bytes: info.bytes, problem });
        }
        Ok(out)
    }

    /// Removes entries last used more than `max_age` ago, then the least recently used ones
    /// until the rest fit in `max_size` bytes; and the temporary files of stores that crashed
    /// (unlocked, see [`crate::atomic::remove_stale_temp_files`]).
    pub fn prune(&self, max_size: Option<u64>, max_age: Option<Duration>) -> io::Result<PruneReport> {
        let mut report = PruneReport::default();
        // A store writes `.KEY.vlf.XXXXXX.tmp` beside `KEY.vlf`: clean up per entry name.
        let mut targets = std::collections::BTreeSet::new();
        for item in std::fs::read_dir(&self.dir)? {
            let name = item?.file_name().to_string_lossy().into_owned();
            if let Some(target) = name.strip_prefix('.').and_then(|n| Some(&n[..n.strip_suffix(".tmp")?.rfind('.')?]))
                && is_entry_name(target).is_some()
            {
                targets.insert(target.to_string());
            }
        }
        for target in targets {
            report.stale_temp_files += remove_stale_temp_files(&self.dir.join(target));
        }
        // Oldest last.
        let entries = self.list()?;
        let mut kept_bytes: u64 = entries.iter().map(|e| e.bytes).sum();
        let mut kept = entries.len();
        for e in entries.iter().rev() {
            let too_old = max_age.is_some_and(|age| e.age_seconds > age.as_secs_f64());
            let too_big = max_size.is_some_and(|size| kept_bytes > size);
            if too_old || too_big {
                remove_if_present(&e.path)?;
                report.removed.push(e.key.clone());
                report.removed_bytes += e.bytes;
                kept_bytes -= e.bytes;
                kept -= 1;
            }
        }
        report.kept = kept;
        report.kept_bytes = kept_bytes;
        Ok(report)
    }
}

fn remove_if_present(path: &Path) -> io::Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

fn describe(r: &FieldReader<'_>) -> FieldInfo {
    FieldInfo {
        format_version: format!("{}.{}", r.header.version_major, r.header.version_minor),
        input_hash: hex(&r.header.input_hash),
        content_hash: hex(&r.header.content_hash),
        triangles: r.scene.triangle_count,
        directions: r.params.direction_count,
        tile_resolution: r.params.tile_resolution,
        inputs: r
            .inputs
            .iter()
            .map(|i| r.string(i.name_offset, i.name_length).unwrap_or("<invalid name>").to_string())
            .collect(),
    }
}

/// Parses `30d`, `12h`, `90m`, `3600s`, `2w` or a bare number of seconds.
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    let t = s.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let forms = "write a number and a unit s, m, h, d or w, such as 30d, 12h, 90m or 3600s";
    // A plain decimal number: `1e3` is not one (its `e3` would read as a unit).
    let plain = |n: &str| n.bytes().all(|b| b.is_ascii_digit() || b == b'.' || b == b'-' || b == b'+');
    let value: f64 = num
        .trim()
        .parse()
        .ok()
        .filter(|_| plain(num.trim()))
        .ok_or_else(|| format!("`{s}` is not a duration: {forms}"))?;
    let scale = match unit.trim() {
        "" | "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        "d" => 86400.0,
        "w" => 7.0 * 86400.0,
        _ => return Err(format!("`{s}` is not a duration: {forms}")),
    };
    let secs = value * scale;
    if !(0.0..1e15).contains(&secs) {
        return Err(format!("`{s}` is not a non-negative duration"));
    }
    Ok(Duration::from_secs_f64(secs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse() {
        assert_eq!(parse_duration("90m"), Ok(Duration::from_secs(5400)));
        assert_eq!(parse_duration("2d"), Ok(Duration::from_secs(172_800)));
        assert_eq!(parse_duration("1w"), Ok(Duration::from_secs(604_800)));
        assert_eq!(parse_duration("15"), Ok(Duration::from_secs(15)));
        assert!(parse_duration("3 fortnights").is_err());
        assert!(parse_duration("-1h").is_err());
        for bad in ["1e3", "3 fortnights", "soon", "1.5.2h"] {
            let e = parse_duration(bad).unwrap_err();
            assert!(e.starts_with(&format!("`{bad}` is not a duration: write a number and a unit")), "{e}");
        }
    }

    #[test]
    fn entry_names_are_keys() {
        let key = "ab".repeat(32);
        assert_eq!(is_entry_name(&format!("{key}.vlf")), Some(key.as_str()));
        assert_eq!(is_entry_name(&format!(".{key}.vlf.x1y2.tmp")), None);
        assert_eq!(is_entry_name("notes.vlf"), None);
    }
}
