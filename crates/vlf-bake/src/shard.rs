//! Sharded bakes (`formats/vlf-shard.md`): `bake --shard K/N` bakes the directions
//! `⌊K·l/N⌋ .. ⌊(K+1)·l/N⌋` into a shard file ([`crate::writer::write_into`]), and [`merge`] checks a
//! set of shards and streams them into the field a single bake of the same inputs writes, byte
//! for byte.
//!
//! The merged field's sections are laid out in the order of the shards' tables (without the
//! SHARD record): every shared section is copied whole from the first shard, whatever its kind (so
//! sections this code does not know flow through unchanged), and the per-direction sections are
//! concatenated in shard order, with BEAMS re-based and STATISTICS summed. Every byte of every
//! shard is hashed and compared with its table on the way; the output is a temporary file renamed
//! over the path only when everything checked out.

use crate::atomic::AtomicFile;
use crate::progress::Progress;
use crate::sections::BAKER_REVISION;
use crate::statistics::merge_stats;
use std::fmt;
use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use vlf_format::shard::{
    PER_DIRECTION_KINDS, SHARD_KIND, SHARD_MAGIC, ShardRecord, is_per_direction, shard_directions, shared_hash,
};
use vlf_format::{
    BeamRecord, FieldFile, HEADER_SIZE, Header, MAGIC, ParamsRecord, SectionEntry, SectionKind, StatisticsRecord,
    TABLE_ENTRY_SIZE, VERSION_MAJOR, VERSION_MINOR, codec, hex, kind_name,
};

/// The most shards a bake may be split into.
pub const MAX_SHARDS: u32 = 65536;

/// `--shard K/N`: shard `K` (counted from 0) of `N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ShardSpec {
    pub index: u32,
    pub count: u32,
}

impl FromStr for ShardSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not a shard: write K/N, shard K (counted from 0) of N, e.g. 0/4 … 3/4");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        // A whole number, `None` if too large for a u32 (then out of range, not malformed).
        let number = |t: &str| {
            let t = t.trim();
            let digits = t.strip_prefix('+').unwrap_or(t);
            if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(bad());
            }
            Ok(digits.parse::<u32>().ok())
        };
        let (index, count) = (number(k)?, number(n)?);
        let Some(count) = count.filter(|c| (1..=MAX_SHARDS).contains(c)) else {
            return Err(format!("shard count {} in `{s}` is outside 1..={MAX_SHARDS}", n.trim()));
        };
        let Some(index) = index.filter(|i| *i < count) else {
            return Err(format!(
                "shard index {} in `{s}` must be below the count {count} (shards are 0..{count})",
                k.trim()
            ));
        };
        Ok(ShardSpec { index, count })
    }
}

impl ShardSpec {
    /// The directions `⌊K·l/N⌋ .. ⌊(K+1)·l/N⌋` this shard holds of a field of `direction_count`
    /// directions (`formats/vlf-shard.md` §2).
    pub fn directions(&self, direction_count: u32) -> std::ops::Range<u32> {
        shard_directions(self.index, self.count, direction_count)
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Why a set of shards cannot be merged. Every variant names the file(s) at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShardError {
    #[error("cannot read {path}: {error}")]
    Io { path: PathBuf, error: io::Error },
    #[error("cannot write {path}: {error}")]
    Write { path: PathBuf, error: io::Error },
    #[error("no shards to merge")]
    NoShards,
    #[error("{path} is not a VLF shard: {problem}")]
    NotShard { path: PathBuf, problem: String },
    #[error(
        "{path} is a complete field, not a shard: merge takes the files `vlf-bake bake --shard K/N` writes (a field needs no merge)"
    )]
    FullField { path: PathBuf },
    #[error("{path} is a corrupt shard: {problem}")]
    Corrupt { path: PathBuf, problem: String },
    #[error(
        "{path} was written by another version of vlf-bake ({found}); this one writes {expected}: bake and merge with the same vlf-bake"
    )]
    OtherVersion { path: PathBuf, found: String, expected: String },
    #[error("{path} does not belong with {other}: {problem}")]
    Mismatch { path: PathBuf, other: PathBuf, problem: String },
    #[error("shard {shard} is given twice: {first} and {second}")]
    Duplicate { shard: ShardSpec, first: PathBuf, second: PathBuf },
    #[error("{missing} missing (a set of {count} shards); given: {given}")]
    Missing { missing: String, count: u32, given: String },
    #[error(
        "the merged field is {length} bytes, over the --max-bytes ceiling of {ceiling} bytes the shards were baked with (as a single bake would have said); lower --directions or --tiles, or raise --max-bytes"
    )]
    OverBudget { length: u64, ceiling: u64 },
}

/// A shard file whose header, table and small sections checked out: everything in the
/// "belongs together" checks, read without touching the bulk of the file.
pub struct ShardFile {
    pub path: PathBuf,
    file: File,
    pub header: Header,
    pub table: Vec<SectionEntry>,
    pub record: ShardRecord,
    pub params: ParamsRecord,
}

/// Reads exactly `buf.len()` bytes at `offset` without moving a shared cursor.
fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            match std::os::windows::fs::FileExt::seek_read(file, buf, offset)? {
                0 => return Err(io::ErrorKind::UnexpectedEof.into()),
                n => {
                    buf = &mut buf[n..];
                    offset += n as u64;
                }
            }
        }
        Ok(())
    }
}

/// Copy granularity of the merge.
const CHUNK: usize = 4 << 20;

impl ShardFile {
    /// Opens `path` and checks it as a shard: magic, header, table and content hash (`formats/vlf.md`
    /// §7), the SHARD record and PARAMS (hashes checked), the version, the element counts of the
    /// per-direction sections and the shared hash. Time independent of the shard's size; the
    /// section hashes of the bulk are checked while merging.
    pub fn open(path: &Path) -> Result<ShardFile, ShardError> {
        let path_buf = path.to_path_buf();
        let io_err = |error| ShardError::Io { path: path_buf.clone(), error };
        let corrupt = |problem: String| ShardError::Corrupt { path: path.to_path_buf(), problem };
        // Only a regular file: opening a pipe waits for a writer, forever if none comes.
        let (file, meta) = vlf_runtime::regular::open_regular_file(path).map_err(io_err)?;
        let len = meta.len();
        let mut head = vec![0u8; HEADER_SIZE.min(len as usize)];
        read_exact_at(&file, &mut head, 0).map_err(io_err)?;
        if head.len() >= 8 && head[..8] == MAGIC {
            return Err(ShardError::FullField { path: path.to_path_buf() });
        }
        if head.len() < 8 || head[..8] != SHARD_MAGIC {
            let problem = if head.len() < 8 {
                format!("it is {len} bytes long")
            } else {
                format!("bad magic number {:02x?}", &head[..8])
            };
            return Err(ShardError::NotShard { path: path.to_path_buf(), problem });
        }
        let header = vlf_format::check_header(&head, len, &SHARD_MAGIC).map_err(|e| corrupt(e.to_string()))?;
        if (header.version_major, header.version_minor) != (VERSION_MAJOR, VERSION_MINOR) {
            return Err(ShardError::OtherVersion {
                path: path.to_path_buf(),
                found: format!("format {}.{}", header.version_major, header.version_minor),
                expected: format!("format {VERSION_MAJOR}.{VERSION_MINOR}"),
            });
        }
        let mut head_and_table = vec![0u8; HEADER_SIZE + header.section_count as usize * TABLE_ENTRY_SIZE];
        read_exact_at(&file, &mut head_and_table, 0).map_err(io_err)?;
        let table = vlf_format::check_table(&head_and_table, len).map_err(|e| corrupt(e.to_string()))?;

        let small = |e: &SectionEntry| -> Result<Vec<u8>, ShardError> {
            let mut bytes = vec![0u8; e.raw_length as usize];
            read_exact_at(&file, &mut bytes, e.offset).map_err(io_err)?;
            if *blake3::hash(&bytes).as_bytes() != e.raw_hash {
                return Err(corrupt(format!("section {} does not match its hash", kind_name(e.kind))));
            }
            Ok(bytes)
        };
        if let Some(e) = table.iter().find(|e| e.codec != codec::RAW) {
            return Err(corrupt(format!("section {} is compressed; shards are always raw", kind_name(e.kind))));
        }
        let first = table.first().filter(|e| e.kind == SHARD_KIND && e.raw_length == size_of::<ShardRecord>() as u64);
        let Some(shard_entry) = first else {
            return Err(corrupt("the first section is not a 64-byte SHARD record".into()));
        };
        let record: ShardRecord = bytemuck::pod_read_unaligned(&small(shard_entry)?);
        let find = |kind: SectionKind| {
            table
                .iter()
                .find(|e| e.kind == kind as u32)
                .ok_or_else(|| corrupt(format!("section {} is missing", kind.name())))
        };
        // Only what the merge itself reads is required here: every other section is carried over
        // whole, whatever its kind (a format minor may add optional ones), and the field reader
        // checks the merged field's required sections like any other field's.
        for kind in PER_DIRECTION_KINDS {
            find(kind)?;
        }
        let params_entry = find(SectionKind::Params)?;
        if params_entry.raw_length != size_of::<ParamsRecord>() as u64 {
            return Err(corrupt("PARAMS is not one record".into()));
        }
        let params: ParamsRecord = bytemuck::pod_read_unaligned(&small(params_entry)?);

        if record.baker_revision != BAKER_REVISION {
            return Err(ShardError::OtherVersion {
                path: path.to_path_buf(),
                found: format!("baker revision {}", record.baker_revision),
                expected: format!("baker revision {BAKER_REVISION}"),
            });
        }
        let range = shard_directions(record.shard_index, record.shard_count, record.direction_count);
        let consistent = record.shard_count >= 1
            && record.shard_count <= MAX_SHARDS
            && record.shard_index < record.shard_count
            && record.reserved == 0
            && (record.first_direction..record.end_direction) == range
            && record.direction_count == params.direction_count
            && record.field_section_count as usize + 1 == table.len();
        if !consistent {
            return Err(corrupt(format!("the SHARD record is inconsistent: {record:?}")));
        }
        let directions = range.len() as u64;
        let n2 = params.tile_resolution as u64 * params.tile_resolution as u64;
        for (kind, elements) in
            [(SectionKind::Beams, directions), (SectionKind::Tiles, directions * n2), (SectionKind::Statistics, 1)]
        {
            let e = find(kind)?;
            if e.raw_length != elements * e.element_size as u64 {
                return Err(corrupt(format!(
                    "section {} has {} elements, the shard's {directions} directions need {elements}",
                    kind.name(),
                    e.raw_length / e.element_size as u64
                )));
            }
        }
        let shared = table[1..].iter().filter(|e| !is_per_direction(e.kind));
        if shared_hash(shared) != record.shared_hash {
            return Err(corrupt("the shared sections do not match the SHARD record's shared_hash".into()));
        }
        Ok(ShardFile { path: path.to_path_buf(), file, header, table, record, params })
    }

    /// `K/N` of this shard.
    pub fn spec(&self) -> ShardSpec {
        ShardSpec { index: self.record.shard_index, count: self.record.shard_count }
    }

    /// The entry of a per-direction section (present: checked at open).
    fn entry(&self, kind: SectionKind) -> &SectionEntry {
        self.table.iter().find(|e| e.kind == kind as u32).expect("checked at open")
    }

    fn corrupt(&self, problem: String) -> ShardError {
        ShardError::Corrupt { path: self.path.clone(), problem }
    }

    fn io_err(&self, error: io::Error) -> ShardError {
        ShardError::Io { path: self.path.clone(), error }
    }

    /// Streams section `e` through `sink` in chunks, hashing it, and fails naming the section if
    /// the bytes do not match the table.
    fn stream(
        &self,
        e: &SectionEntry,
        buf: &mut [u8],
        sink: &mut dyn FnMut(&[u8]) -> Result<(), ShardError>,
    ) -> Result<(), ShardError> {
        let mut hasher = blake3::Hasher::new();
        let mut done = 0u64;
        while done < e.raw_length {
            let n = buf.len().min((e.raw_length - done) as usize);
            read_exact_at(&self.file, &mut buf[..n], e.offset + done).map_err(|e| self.io_err(e))?;
            hasher.update(&buf[..n]);
            sink(&buf[..n])?;
            done += n as u64;
        }
        if *hasher.finalize().as_bytes() != e.raw_hash {
            return Err(self.corrupt(format!("section {} does not match its hash", kind_name(e.kind))));
        }
        Ok(())
    }

    /// A small section, read whole and checked against its hash.
    fn read_section(&self, kind: SectionKind) -> Result<Vec<u8>, ShardError> {
        let e = *self.entry(kind);
        let mut out = Vec::with_capacity(e.raw_length as usize);
        let mut buf = vec![0u8; CHUNK.min(e.raw_length as usize).max(1)];
        self.stream(&e, &mut buf, &mut |b| {
            out.extend_from_slice(b);
            Ok(())
        })?;
        Ok(out)
    }

    /// Checks that the padding between the table and the sections is zero (under 64 bytes each in
    /// a shard vlf-bake wrote).
    fn check_padding(&self) -> Result<(), ShardError> {
        let mut pos = (HEADER_SIZE + TABLE_ENTRY_SIZE * self.table.len()) as u64;
        let mut gap = [0u8; 4096];
        for e in &self.table {
            while pos < e.offset {
                let n = gap.len().min((e.offset - pos) as usize);
                read_exact_at(&self.file, &mut gap[..n], pos).map_err(|e| self.io_err(e))?;
                if let Some(i) = gap[..n].iter().position(|&b| b != 0) {
                    return Err(self.corrupt(format!("padding byte at offset {} is not zero", pos + i as u64)));
                }
                pos += n as u64;
            }
            pos = e.offset + e.raw_length;
        }
        Ok(())
    }
}

/// The request a PARAMS record holds (`formats/vlf.md` §3.3), as text for messages.
fn requested(p: &ParamsRecord) -> String {
    let auto = |v: Option<u32>| v.map_or("automatic".to_string(), |v| v.to_string());
    format!(
        "requested directions {}, tiles {}, leaf size {}, max depth {}, max bytes {}, max bytes per triangle {}",
        auto(p.requested_directions()),
        auto(p.requested_tiles()),
        p.leaf_size,
        p.max_depth,
        p.max_bytes,
        p.max_bytes_per_triangle
    )
}

/// The parameters a PARAMS record holds, as text for messages.
fn chosen(p: &ParamsRecord) -> String {
    format!("{} directions × {}² tiles, margin {:e}", p.direction_count, p.tile_resolution, p.margin)
}

/// Checks that `shards` are every shard of one bake, each once, and returns them in index order.
pub fn check_set(shards: Vec<ShardFile>) -> Result<Vec<ShardFile>, ShardError> {
    let Some(first) = shards.first() else { return Err(ShardError::NoShards) };
    let kinds = |s: &ShardFile| s.table.iter().map(|e| e.kind).collect::<Vec<u32>>();
    for s in &shards[1..] {
        let mismatch =
            |problem: String| Err(ShardError::Mismatch { path: s.path.clone(), other: first.path.clone(), problem });
        if s.record.shard_count != first.record.shard_count {
            return mismatch(format!(
                "it is shard {} but {} is shard {}: shards of different splits",
                s.spec(),
                first.path.display(),
                first.spec()
            ));
        }
        // The input hash covers the request; say which of the two differs.
        if requested(&s.params) != requested(&first.params) {
            return mismatch(format!(
                "different parameters ({} vs {})",
                requested(&s.params),
                requested(&first.params)
            ));
        }
        if s.header.input_hash != first.header.input_hash {
            return mismatch(format!(
                "shards of different inputs (input hash {} vs {})",
                hex(&s.header.input_hash),
                hex(&first.header.input_hash)
            ));
        }
        if s.params != first.params {
            return mismatch(format!(
                "same inputs and request but different parameters were chosen ({} vs {})",
                chosen(&s.params),
                chosen(&first.params)
            ));
        }
        if s.record.shared_hash != first.record.shared_hash || kinds(s) != kinds(first) {
            return mismatch("same inputs and parameters but different shared sections or layout".into());
        }
    }
    let count = first.record.shard_count;
    let mut slots: Vec<Option<ShardFile>> = (0..count).map(|_| None).collect();
    for s in shards {
        let slot = &mut slots[s.record.shard_index as usize];
        if let Some(prev) = slot {
            return Err(ShardError::Duplicate { shard: s.spec(), first: prev.path.clone(), second: s.path });
        }
        *slot = Some(s);
    }
    let missing: Vec<String> =
        slots.iter().enumerate().filter(|(_, s)| s.is_none()).map(|(k, _)| format!("{k}/{count}")).collect();
    if !missing.is_empty() {
        let given: Vec<String> =
            slots.iter().flatten().map(|s| format!("{} ({})", s.spec(), s.path.display())).collect();
        let missing = match missing.len() {
            1 => format!("shard {} is", missing[0]),
            _ => format!("shards {} are", missing.join(", ")),
        };
        return Err(ShardError::Missing { missing, count, given: given.join(", ") });
    }
    Ok(slots.into_iter().map(|s| s.expect("checked")).collect())
}

/// One merged shard.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PartInfo {
    pub path: PathBuf,
    pub shard: String,
    pub bytes: u64,
    pub content_hash: String,
}

/// What a merge wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MergeSummary {
    pub output: PathBuf,
    pub shards: u32,
    /// The shards in index order.
    pub parts: Vec<PartInfo>,
    pub directions: u32,
    pub tile_resolution: u32,
    pub bytes: u64,
    pub content_hash: String,
    pub input_hash: String,
    /// Seconds checking the shards' headers and tables, and copying and hashing their sections.
    pub check_seconds: f64,
    pub copy_seconds: f64,
    #[serde(skip)]
    pub header: Header,
    #[serde(skip)]
    pub params: ParamsRecord,
}

/// Merges the shard files `parts` (any order) into the field `output`, atomically; refuses a
/// set that is not every shard of one bake exactly once, or any corrupt shard, naming the files.
pub fn merge(parts: &[PathBuf], output: &Path, progress: &dyn Progress) -> Result<MergeSummary, ShardError> {
    let started = std::time::Instant::now();
    let shards = parts.iter().map(|p| ShardFile::open(p)).collect::<Result<Vec<_>, _>>()?;
    let shards = check_set(shards)?;
    for s in &shards {
        s.check_padding()?;
    }
    let check_seconds = started.elapsed().as_secs_f64();
    let copying = std::time::Instant::now();
    let write_err = |error| ShardError::Write { path: output.to_path_buf(), error };
    let tmp = AtomicFile::create(output).map_err(write_err)?;
    let header = write_merged(&shards, tmp.file(), output, progress)?;
    // Explicit parameters are held to --max-bytes (`bake` refuses such a field; each shard could
    // only check its own part).
    let p = &shards[0].params;
    if !p.is_automatic() && header.file_length > p.max_bytes {
        return Err(ShardError::OverBudget { length: header.file_length, ceiling: p.max_bytes });
    }
    tmp.commit().map_err(write_err)?;
    progress.end();
    let first = &shards[0];
    Ok(MergeSummary {
        output: output.to_path_buf(),
        shards: shards.len() as u32,
        parts: shards
            .iter()
            .map(|s| PartInfo {
                path: s.path.clone(),
                shard: s.spec().to_string(),
                bytes: s.header.file_length,
                content_hash: hex(&s.header.content_hash),
            })
            .collect(),
        directions: first.params.direction_count,
        tile_resolution: first.params.tile_resolution,
        bytes: header.file_length,
        content_hash: hex(&header.content_hash),
        input_hash: hex(&header.input_hash),
        check_seconds,
        copy_seconds: copying.elapsed().as_secs_f64(),
        header,
        params: first.params,
    })
}

/// Writes the field of a checked, ordered shard set into `out` (see the module documentation).
fn write_merged(
    shards: &[ShardFile],
    out: &File,
    output: &Path,
    progress: &dyn Progress,
) -> Result<Header, ShardError> {
    let write_err = |error| ShardError::Write { path: output.to_path_buf(), error };
    let first = &shards[0];
    let layout = &first.table[1..];
    let total = |kind: u32| {
        shards.iter().map(|s| s.table.iter().find(|e| e.kind == kind).map_or(0, |e| e.raw_length)).sum::<u64>()
    };
    let mut f = FieldFile::create(out.try_clone().map_err(write_err)?, layout.len()).map_err(write_err)?;
    let mut writers = Vec::with_capacity(layout.len());
    for e in layout {
        let length = match SectionKind::from_u32(e.kind) {
            Some(SectionKind::Statistics) => e.raw_length,
            Some(_) if is_per_direction(e.kind) => total(e.kind),
            _ => e.raw_length,
        };
        writers.push(f.reserve_kind(e.kind, e.element_size, length).map_err(write_err)?);
    }
    let bytes_total: u64 = shards.iter().map(|s| s.header.file_length).sum();
    progress.begin("merging shards", bytes_total);
    let mut buf = vec![0u8; CHUNK];

    // Shared sections: copied from the first shard, checked in every shard.
    for (e, w) in layout.iter().zip(writers.iter_mut()) {
        if is_per_direction(e.kind) {
            continue;
        }
        first.stream(e, &mut buf, &mut |b| w.write_all(b).map_err(write_err))?;
        progress.advance(e.raw_length);
        for s in &shards[1..] {
            let own = s.table.iter().find(|o| o.kind == e.kind).expect("same layout, checked");
            s.stream(own, &mut buf, &mut |_| Ok(()))?;
            progress.advance(own.raw_length);
        }
    }

    // Per-direction sections, shard by shard in index order.
    let position = |kind: SectionKind| layout.iter().position(|e| e.kind == kind as u32).expect("checked at open");
    let mut leaves_base = 0u64;
    let mut stats = StatisticsRecord::zeroed_record();
    for s in shards {
        let n2 = s.params.tile_resolution as u64 * s.params.tile_resolution as u64;
        for kind in [SectionKind::Tiles, SectionKind::Leaves] {
            let e = *s.entry(kind);
            let w = &mut writers[position(kind)];
            s.stream(&e, &mut buf, &mut |b| w.write_all(b).map_err(write_err))?;
            progress.advance(e.raw_length);
        }
        let beams: Vec<BeamRecord> = bytemuck::pod_collect_to_vec(&s.read_section(SectionKind::Beams)?);
        let mut words = 0u64;
        for (i, b) in beams.iter().enumerate() {
            if b.leaves_base != words {
                return Err(s.corrupt(format!(
                    "BEAMS record {i} does not follow the previous one (leaves_base {}; expected {words})",
                    b.leaves_base
                )));
            }
            words = words.saturating_add(b.leaves_words);
        }
        if words.checked_mul(vlf_format::size::LEAF_WORD) != Some(s.entry(SectionKind::Leaves).raw_length) {
            return Err(s.corrupt("BEAMS do not cover LEAVES exactly".into()));
        }
        let rebased: Vec<BeamRecord> =
            beams.iter().map(|b| BeamRecord { leaves_base: b.leaves_base + leaves_base, ..*b }).collect();
        writers[position(SectionKind::Beams)].write_all(bytemuck::cast_slice(&rebased)).map_err(write_err)?;
        leaves_base += words;
        let shard_stats: StatisticsRecord = bytemuck::pod_read_unaligned(&s.read_section(SectionKind::Statistics)?);
        if shard_stats.tile_count != beams.len() as u64 * n2 {
            return Err(s.corrupt(format!(
                "STATISTICS count {} tiles, the shard has {}",
                shard_stats.tile_count,
                beams.len() as u64 * n2
            )));
        }
        merge_stats(&mut stats, &shard_stats);
        progress.advance(s.entry(SectionKind::Beams).raw_length + s.entry(SectionKind::Statistics).raw_length);
    }
    writers[position(SectionKind::Statistics)].write_all(bytemuck::bytes_of(&stats)).map_err(write_err)?;

    progress.end();
    progress.begin("writing", 1);
    for w in writers {
        f.finish_section(w).map_err(write_err)?;
    }
    let (_, header) = f.finish(first.header.input_hash).map_err(write_err)?;
    Ok(header)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shard_spec_is_k_of_n_counted_from_zero() {
        assert_eq!("0/4".parse(), Ok(ShardSpec { index: 0, count: 4 }));
        assert_eq!(" 3 / 4 ".parse(), Ok(ShardSpec { index: 3, count: 4 }));
        assert_eq!("0/1".parse(), Ok(ShardSpec { index: 0, count: 1 }));
        assert_eq!("65535/65536".parse(), Ok(ShardSpec { index: 65535, count: MAX_SHARDS }));
        for text in ["0/4", "3/4", "12/65536"] {
            assert_eq!(text.parse::<ShardSpec>().unwrap().to_string(), text);
        }
    }

    #[test]
    fn bad_shard_specs_are_refused_saying_why() {
        for (text, says) in [
            ("4/4", "shard index 4 in `4/4` must be below the count 4 (shards are 0..4)"),
            ("7/3", "must be below the count 3"),
            ("0/0", "shard count 0 in `0/0` is outside 1..=65536"),
            ("0/65537", "shard count 65537 in `0/65537` is outside 1..=65536"),
            ("0/4294967296", "shard count 4294967296 in `0/4294967296` is outside 1..=65536"),
            (
                "0/99999999999999999999999",
                "shard count 99999999999999999999999 in `0/99999999999999999999999` is outside",
            ),
            ("4294967296/4", "shard index 4294967296 in `4294967296/4` must be below the count 4"),
            ("0/-1", "`0/-1` is not a shard"),
            ("1", "`1` is not a shard: write K/N, shard K (counted from 0) of N, e.g. 0/4 … 3/4"),
            ("a/4", "`a/4` is not a shard"),
            ("1/b", "`1/b` is not a shard"),
            ("-1/4", "`-1/4` is not a shard"),
            ("1/2/3", "`1/2/3` is not a shard"),
            ("", "`` is not a shard"),
        ] {
            let e = text.parse::<ShardSpec>().unwrap_err();
            assert!(e.contains(says), "`{text}`: {e}");
        }
    }

    /// The shards of a split, parsed as `--shard` gives them, hold every direction exactly once, in
    /// order, their sizes differing by at most one direction; with more shards than directions
    /// some hold none.
    #[test]
    fn the_shards_of_a_split_cover_every_direction_exactly_once() {
        for l in [1u32, 3, 9, 33, 129, 2049] {
            for n in [1u32, 2, 3, 4, 5, 7, 64, 4096] {
                let mut held = vec![0u32; l as usize];
                let mut next = 0;
                let mut sizes = Vec::new();
                for k in 0..n {
                    let spec: ShardSpec = format!("{k}/{n}").parse().unwrap();
                    let range = spec.directions(l);
                    assert_eq!(range.start, next, "shard {spec} of {l} directions does not follow the previous one");
                    next = range.end;
                    sizes.push(range.len());
                    for j in range {
                        held[j as usize] += 1;
                    }
                }
                assert_eq!(next, l, "{n} shards of {l} directions end early");
                assert!(held.iter().all(|&c| c == 1), "{n} shards of {l} directions: {held:?}");
                let (min, max) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(max - min <= 1, "{n} shards of {l} directions: sizes {sizes:?}");
                assert_eq!(*min == 0, n > l, "{n} shards of {l} directions: sizes {sizes:?}");
            }
        }
        // 33 directions in 4 shards: ⌊33k/4⌋.
        let ranges: Vec<_> = (0..4).map(|k| ShardSpec { index: k, count: 4 }.directions(33)).collect();
        assert_eq!(ranges, [0..8, 8..16, 16..24, 24..33]);
    }
}
