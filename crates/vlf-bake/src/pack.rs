//! `vlf-bake pack` and `vlf-bake unpack`: transport compression of field files
//! (`formats/vlf.md` §8). The bytes (layouts, frames, checks) are `vlf_format::pack`; this module
//! moves them between files: sections compressed in parallel into spill files, a packed field
//! decoded streaming, both written atomically.
//!
//! Memory is bounded whatever the field's size: a packer holds one zstd context and two 1 MiB
//! buffers per section in flight (at most one per worker thread), an unpacker one decoder (its
//! window is at most 8 MiB at the levels `pack` writes, and zstd refuses frames asking for more
//! than 128 MiB) and its buffers.

use crate::atomic::{AtomicFile, parent_dir};
use crate::progress::Progress;
use rayon::prelude::*;
use serde::Serialize;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;
use vlf_format::pack::{self, StreamError};
use vlf_format::{AlignedWriter, FormatError, SectionEntry, codec, hex, kind_name};

pub use vlf_format::pack::{DEFAULT_LEVEL, LEVELS};

/// Why packing or unpacking failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PackError {
    #[error("{context}: {error}")]
    Io { context: String, error: io::Error },
    #[error("{path}: {error}")]
    Format { path: PathBuf, error: FormatError },
    #[error("{path} is already packed; unpack it first (`vlf-bake unpack`) to pack it at another level")]
    AlreadyPacked { path: PathBuf },
    #[error("{path} is not packed (every section is raw): there is nothing to unpack")]
    NotPacked { path: PathBuf },
    #[error(
        "{path}: the sections are not at their canonical offsets (formats/vlf.md §8.1), so unpacking could not reproduce the file byte for byte; rewrite it with `vlf-bake bake`"
    )]
    NotCanonical { path: PathBuf },
    #[error("zstd level {0} is outside {min}..={max}", min = LEVELS.start(), max = LEVELS.end())]
    Level(i32),
    #[error("{path} changed while it was being read")]
    Changed { path: PathBuf },
}

/// One section of a packed or unpacked field.
#[derive(Debug, Clone, Serialize)]
pub struct SectionSummary {
    pub name: String,
    pub codec: &'static str,
    pub raw_length: u64,
    pub stored_length: u64,
}

/// What `vlf-bake pack` did (and its `--json` keys). Speeds are raw (uncompressed) megabytes
/// (10⁶ bytes) per second; `ratio` is raw bytes over packed bytes.
#[derive(Debug, Serialize)]
pub struct PackSummary {
    pub input: PathBuf,
    pub output: PathBuf,
    pub level: i32,
    pub raw_bytes: u64,
    pub packed_bytes: u64,
    pub ratio: f64,
    pub seconds: f64,
    pub mb_per_s: f64,
    /// The packed file's content hash.
    pub content_hash: String,
    /// The raw field's content hash, which `unpack` reproduces.
    pub raw_content_hash: String,
    pub sections: Vec<SectionSummary>,
}

/// What `vlf-bake unpack` did (and its `--json` keys), in the units of [`PackSummary`].
#[derive(Debug, Serialize)]
pub struct UnpackSummary {
    pub input: PathBuf,
    pub output: PathBuf,
    pub packed_bytes: u64,
    pub raw_bytes: u64,
    pub ratio: f64,
    pub seconds: f64,
    pub mb_per_s: f64,
    /// The raw field's content hash.
    pub content_hash: String,
}

fn codec_name(c: u32) -> &'static str {
    if c == codec::RAW { "raw" } else { "zstd" }
}

/// The sections of a table, for summaries.
pub fn section_summaries(table: &[SectionEntry]) -> Vec<SectionSummary> {
    table
        .iter()
        .map(|e| SectionSummary {
            name: kind_name(e.kind),
            codec: codec_name(e.codec),
            raw_length: e.raw_length,
            stored_length: e.stored_length,
        })
        .collect()
}

fn io_error(context: impl FnOnce() -> String) -> impl FnOnce(io::Error) -> PackError {
    move |error| PackError::Io { context: context(), error }
}

fn stream_error(path: &Path, context: impl FnOnce() -> String) -> impl FnOnce(StreamError) -> PackError {
    move |e| match e {
        StreamError::Io(error) => PackError::Io { context: context(), error },
        StreamError::Format(error) => PackError::Format { path: path.to_path_buf(), error },
    }
}

fn per_second(bytes: u64, seconds: f64) -> f64 {
    bytes as f64 / 1e6 / seconds.max(1e-9)
}

/// Packs the raw field `input` into `output` (atomically) at zstd level `level`: every section
/// whose zstd frame is shorter than its raw bytes is stored compressed, the rest raw (§8.2).
/// Sections are compressed in parallel on rayon's current pool, each on one thread, so the output
/// does not depend on the thread count. The input's hashes and padding are checked on the way.
pub fn pack_path(input: &Path, output: &Path, level: i32, progress: &dyn Progress) -> Result<PackSummary, PackError> {
    if !LEVELS.contains(&level) {
        return Err(PackError::Level(level));
    }
    let started = Instant::now();
    let reading = || format!("cannot read {}", input.display());
    let writing = || format!("cannot write {}", output.display());
    let mut file = File::open(input).map_err(io_error(reading))?;
    let (header, table) = pack::read_head(&mut file).map_err(stream_error(input, reading))?;
    if pack::is_packed(&table) {
        return Err(PackError::AlreadyPacked { path: input.to_path_buf() });
    }
    if !pack::is_canonical(&table) {
        return Err(PackError::NotCanonical { path: input.to_path_buf() });
    }
    pack::check_padding(&mut file, &table).map_err(stream_error(input, reading))?;

    // Each section's frame goes to an anonymous spill file; the biggest sections start first so
    // that they run side by side. Results come back in table order.
    let dir = parent_dir(output);
    let mut order: Vec<usize> = (0..table.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(table[i].raw_length));
    progress.begin("packing", header.file_length);
    let compressed: Result<Vec<(usize, Option<Spill>)>, PackError> = order
        .par_iter()
        .with_max_len(1)
        .map(|&i| compress_section(input, &table[i], level, &dir, progress).map(|spill| (i, spill)))
        .collect();
    progress.end();
    let mut spills: Vec<Option<Spill>> = (0..table.len()).map(|_| None).collect();
    for (i, spill) in compressed? {
        spills[i] = spill;
    }

    let mut packed = table.clone();
    for (e, spill) in packed.iter_mut().zip(&spills) {
        if let Some((_, stored)) = spill {
            e.codec = codec::ZSTD;
            e.stored_length = *stored;
        }
    }
    // Sections only shrink, so the packed file is no longer than the raw one.
    let packed_header = pack::lay_out(&header, &mut packed).expect("a packed field is no longer than its raw field");

    progress.begin("writing", packed_header.file_length);
    let out = AtomicFile::create(output).map_err(io_error(writing))?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, out.file());
        let head = pack::head_bytes(&packed_header, &packed);
        w.write_all(&head).map_err(io_error(writing))?;
        let mut pos = head.len() as u64;
        for ((e, raw), spill) in packed.iter().zip(&table).zip(&mut spills) {
            io::copy(&mut io::repeat(0).take(e.offset - pos), &mut w).map_err(io_error(writing))?;
            match spill {
                Some((frame, stored)) => {
                    let copied = io::copy(&mut frame.take(*stored), &mut w).map_err(io_error(writing))?;
                    if copied != *stored {
                        let error =
                            io::Error::new(io::ErrorKind::UnexpectedEof, "a spill file is shorter than written");
                        return Err(PackError::Io { context: writing(), error });
                    }
                }
                None => {
                    file.seek(SeekFrom::Start(raw.offset)).map_err(io_error(reading))?;
                    pack::copy_raw(raw, &mut file, &mut w, &mut |_| {}).map_err(stream_error(input, reading))?;
                }
            }
            progress.advance(e.offset + e.stored_length - pos);
            pos = e.offset + e.stored_length;
        }
        w.flush().map_err(io_error(writing))?;
    }
    out.commit().map_err(io_error(writing))?;
    progress.end();

    let seconds = started.elapsed().as_secs_f64();
    Ok(PackSummary {
        input: input.to_path_buf(),
        output: output.to_path_buf(),
        level,
        raw_bytes: header.file_length,
        packed_bytes: packed_header.file_length,
        ratio: header.file_length as f64 / packed_header.file_length as f64,
        seconds,
        mb_per_s: per_second(header.file_length, seconds),
        content_hash: hex(&packed_header.content_hash),
        raw_content_hash: hex(&header.content_hash),
        sections: section_summaries(&packed),
    })
}

/// A section's zstd frame in an anonymous temporary file, rewound, and its length.
type Spill = (File, u64);

/// Compresses one raw section of `input` into a spill file in `dir`; `None` if the frame would
/// not be shorter than the raw bytes (the section stays raw).
fn compress_section(
    input: &Path,
    e: &SectionEntry,
    level: i32,
    dir: &Path,
    progress: &dyn Progress,
) -> Result<Option<Spill>, PackError> {
    let reading = || format!("cannot read {}", input.display());
    let spilling = || format!("cannot write a temporary file in {}", dir.display());
    let mut file = File::open(input).map_err(io_error(reading))?;
    file.seek(SeekFrom::Start(e.offset)).map_err(io_error(reading))?;
    let mut spill = tempfile::tempfile_in(dir).map_err(io_error(spilling))?;
    let mut w = BufWriter::with_capacity(1 << 20, &spill);
    // Read and write errors both surface here; the reading context is the likelier one.
    let (stored, hash) = pack::encode_frame(&mut file, e.raw_length, level, &mut w, &mut |n| progress.advance(n))
        .map_err(io_error(|| format!("cannot pack {}", input.display())))?;
    w.flush().map_err(io_error(spilling))?;
    drop(w);
    if hash != e.raw_hash {
        let error = FormatError::SectionHashMismatch {
            kind: kind_name(e.kind),
            stored: hex(&e.raw_hash),
            computed: hex(&hash),
        };
        return Err(PackError::Format { path: input.to_path_buf(), error });
    }
    if stored >= e.raw_length {
        return Ok(None);
    }
    spill.rewind().map_err(io_error(spilling))?;
    Ok(Some((spill, stored)))
}

/// Unpacks the packed field `input` into the raw field `output` (atomically), streaming: every
/// padding byte, frame, length and hash of the input is checked, and the output is the raw field
/// in canonical layout, byte for byte the one that was packed.
pub fn unpack_path(input: &Path, output: &Path, progress: &dyn Progress) -> Result<UnpackSummary, PackError> {
    let started = Instant::now();
    let reading = || format!("cannot read {}", input.display());
    let writing = || format!("cannot write {}", output.display());
    let both = || format!("cannot unpack {} into {}", input.display(), output.display());
    let mut file = File::open(input).map_err(io_error(reading))?;
    let (header, table) = pack::read_head(&mut file).map_err(stream_error(input, reading))?;
    if !pack::is_packed(&table) {
        return Err(PackError::NotPacked { path: input.to_path_buf() });
    }
    let (raw_header, raw_table) = pack::unpacked_layout(&header, &table)
        .map_err(|error| PackError::Format { path: input.to_path_buf(), error })?;

    progress.begin("unpacking", raw_header.file_length);
    let out = AtomicFile::create(output).map_err(io_error(writing))?;
    {
        let head = pack::head_bytes(&raw_header, &raw_table);
        let in_head = (vlf_format::HEADER_SIZE + vlf_format::TABLE_ENTRY_SIZE * table.len()) as u64;
        file.seek(SeekFrom::Start(in_head)).map_err(io_error(reading))?;
        let mut r = BufReader::with_capacity(1 << 20, file);
        // Whole 2 MiB writes, so that the raw field maps with huge pages (`vlf_format::writer`).
        let mut w = AlignedWriter::new(out.file());
        w.write_all(&head).map_err(io_error(writing))?;
        let (mut in_pos, mut out_pos) = (in_head, head.len() as u64);
        for (e, raw) in table.iter().zip(&raw_table) {
            pack::skip_zeros(&mut r, in_pos, e.offset - in_pos).map_err(stream_error(input, reading))?;
            io::copy(&mut io::repeat(0).take(raw.offset - out_pos), &mut w).map_err(io_error(writing))?;
            let mut advance = |n| progress.advance(n);
            if e.codec == codec::RAW {
                pack::copy_raw(e, &mut r, &mut w, &mut advance)
            } else {
                pack::decode_frame_stream(e, &mut r, &mut w, &mut advance)
            }
            .map_err(stream_error(input, both))?;
            in_pos = e.offset + e.stored_length;
            out_pos = raw.offset + raw.raw_length;
        }
        w.flush().map_err(io_error(writing))?;
    }
    out.commit().map_err(io_error(writing))?;
    progress.end();

    let seconds = started.elapsed().as_secs_f64();
    Ok(UnpackSummary {
        input: input.to_path_buf(),
        output: output.to_path_buf(),
        packed_bytes: header.file_length,
        raw_bytes: raw_header.file_length,
        ratio: raw_header.file_length as f64 / header.file_length as f64,
        seconds,
        mb_per_s: per_second(raw_header.file_length, seconds),
        content_hash: hex(&raw_header.content_hash),
    })
}

/// The checks of a packed file that decoding it in memory does not make: that the file at `path`
/// still has the header and table `layout` was read from, and that its padding is zero. With
/// `Field::open` (which checks every frame, length and hash) and the full verification of the
/// decoded field, this is `dump --verify` of a packed field.
pub fn check_packed_file(path: &Path, layout: &pack::PackedLayout) -> Result<(), PackError> {
    let reading = || format!("cannot read {}", path.display());
    let mut file = File::open(path).map_err(io_error(reading))?;
    let (header, table) = pack::read_head(&mut file).map_err(stream_error(path, reading))?;
    if header != layout.header || table != layout.table {
        return Err(PackError::Changed { path: path.to_path_buf() });
    }
    pack::check_padding(&mut file, &table).map_err(stream_error(path, reading))
}
