//! Packed fields (`formats/vlf.md` §8): the same container with sections stored as zstd frames
//! (codec 1), for transport. Byte-level only: which sections are compressed, the frame parameters,
//! the canonical layouts, and decoding with every length and hash checked.
//!
//! A packed field keeps its header's `input_hash` and version and every table entry's `kind`,
//! `raw_length`, `element_size` and `raw_hash`; only `codec`, `offset` and `stored_length` (and so
//! `file_length` and the content hash) change. The raw field is therefore a function of the packed
//! header and table plus the decoded bytes: [`unpacked_layout`] recomputes its header and table,
//! and unpacking a field packed from a canonical raw field reproduces it byte for byte.
//!
//! The layout helpers are always available; encoding and decoding need the `zstd` feature.

use crate::error::{FormatError, hex};
use crate::layout::*;
use crate::reader::{content_hash, parse_head};
use crate::section::*;
use std::io::{self, Read, Seek, SeekFrom};

/// Levels `vlf-bake pack` accepts. The "ultra" levels 20–22 are left out: they need decoder windows
/// of up to 128 MiB and gain little on fields (`docs/benchmarks/pack.md`).
pub const LEVELS: std::ops::RangeInclusive<i32> = 1..=19;

/// The default zstd level of `vlf-bake pack` (`docs/benchmarks/pack.md` explains the choice).
pub const DEFAULT_LEVEL: i32 = 3;

/// Bytes read or decoded per step when streaming a section.
const CHUNK: usize = 1 << 20;

/// The header and table of a packed field as stored, kept by a reader that decoded it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PackedLayout {
    pub header: Header,
    pub table: Vec<SectionEntry>,
}

/// A packed field decoded into memory by [`unpack_in_memory`].
#[derive(Debug)]
pub struct Unpacked {
    /// The raw field, laid out canonically: the bytes `vlf-bake unpack` would write.
    pub bytes: crate::AlignedBytes,
    /// How it was stored.
    pub packed: PackedLayout,
}

/// Why streaming a packed or raw field failed: the bytes, or reading and writing them.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    #[error(transparent)]
    Io(#[from] io::Error),
    #[error(transparent)]
    Format(#[from] FormatError),
}

/// Whether any section of `table` is compressed.
pub fn is_packed(table: &[SectionEntry]) -> bool {
    table.iter().any(|e| e.codec != codec::RAW)
}

/// Places `table`'s stored bytes canonically (§8.1): each section at the first multiple of 64 at
/// or after the end of the table or of the previous section, in table order. Sets every `offset`
/// and returns `template` with `section_count`, `file_length` and `content_hash` recomputed, or
/// `None` if the file would be longer than `u64::MAX` bytes.
pub fn lay_out(template: &Header, table: &mut [SectionEntry]) -> Option<Header> {
    let mut end = (HEADER_SIZE + TABLE_ENTRY_SIZE * table.len()) as u64;
    for e in table.iter_mut() {
        e.offset = end.checked_next_multiple_of(SECTION_ALIGN)?;
        end = e.offset.checked_add(e.stored_length)?;
    }
    let mut header = Header { section_count: table.len() as u32, file_length: end, ..*template };
    header.content_hash = content_hash(&head_bytes(&header, table));
    Some(header)
}

/// Whether every section of `table` sits at its canonical offset (§8.1).
pub fn is_canonical(table: &[SectionEntry]) -> bool {
    let mut end = (HEADER_SIZE + TABLE_ENTRY_SIZE * table.len()) as u64;
    table.iter().all(|e| {
        let at = end.next_multiple_of(SECTION_ALIGN);
        end = e.offset.saturating_add(e.stored_length);
        e.offset == at
    })
}

/// The header and table of the raw field that a (packed or raw) field decodes to (§8.3): every
/// section raw, `stored_length = raw_length`, laid out canonically. For a raw field in canonical
/// layout this is its own header and table.
pub fn unpacked_layout(header: &Header, table: &[SectionEntry]) -> Result<(Header, Vec<SectionEntry>), FormatError> {
    let mut raw: Vec<SectionEntry> =
        table.iter().map(|e| SectionEntry { codec: codec::RAW, stored_length: e.raw_length, ..*e }).collect();
    let header = lay_out(header, &mut raw).ok_or_else(|| FormatError::Invalid {
        section: "section table",
        problem: "the raw lengths add up to more than 2^64 bytes".into(),
    })?;
    Ok((header, raw))
}

/// The bytes of a header followed by its table.
pub fn head_bytes(header: &Header, table: &[SectionEntry]) -> Vec<u8> {
    let mut head = Vec::with_capacity(HEADER_SIZE + TABLE_ENTRY_SIZE * table.len());
    head.extend_from_slice(bytemuck::bytes_of(header));
    head.extend_from_slice(bytemuck::cast_slice(table));
    head
}

/// Reads and checks the header and table of the file `file` (§7; time independent of the file
/// size), returning copies. Leaves the cursor anywhere.
pub fn read_head(file: &mut (impl Read + Seek)) -> Result<(Header, Vec<SectionEntry>), StreamError> {
    let len = file.seek(SeekFrom::End(0))?;
    file.seek(SeekFrom::Start(0))?;
    let mut head = vec![0u8; len.min(HEADER_SIZE as u64) as usize];
    file.read_exact(&mut head)?;
    if head.len() == HEADER_SIZE {
        let count = u32::from_le_bytes(head[32..36].try_into().expect("4 bytes")).min(MAX_SECTIONS);
        let want = (HEADER_SIZE as u64 + TABLE_ENTRY_SIZE as u64 * count as u64).min(len);
        head.resize(want as usize, 0);
        file.read_exact(&mut head[HEADER_SIZE..])?;
    }
    Ok(parse_head(&head, len)?)
}

/// Checks that every padding byte of the file `file`, whose (already checked) table is `table`,
/// is zero (§1): the bytes between the table and the first section and between sections.
pub fn check_padding(file: &mut (impl Read + Seek), table: &[SectionEntry]) -> Result<(), StreamError> {
    let mut pos = (HEADER_SIZE + TABLE_ENTRY_SIZE * table.len()) as u64;
    for e in table {
        file.seek(SeekFrom::Start(pos))?;
        skip_zeros(file, pos, e.offset - pos)?;
        pos = e.offset + e.stored_length;
    }
    Ok(())
}

/// Reads `length` bytes from `from`, which are the file's bytes from offset `at`, and checks that
/// they are zero (padding), in bounded steps whatever the length.
pub fn skip_zeros(from: &mut dyn Read, at: u64, length: u64) -> Result<(), StreamError> {
    let mut buf = [0u8; 4096];
    let mut done = 0u64;
    while done < length {
        let n = buf.len().min((length - done) as usize);
        from.read_exact(&mut buf[..n])?;
        if let Some(i) = buf[..n].iter().position(|&b| b != 0) {
            return Err(FormatError::NonZeroPadding { offset: at + done + i as u64, value: buf[i] }.into());
        }
        done += n as u64;
    }
    Ok(())
}

fn check_hash(e: &SectionEntry, computed: [u8; 32]) -> Result<(), FormatError> {
    if computed == e.raw_hash {
        Ok(())
    } else {
        Err(FormatError::SectionHashMismatch {
            kind: kind_name(e.kind),
            stored: hex(&e.raw_hash),
            computed: hex(&computed),
        })
    }
}

/// Reads exactly `length` bytes from `from` in chunks, passing each to `each`.
fn for_each_chunk(from: &mut dyn Read, length: u64, each: &mut dyn FnMut(&[u8]) -> io::Result<()>) -> io::Result<()> {
    let mut buf = vec![0u8; CHUNK.min(length as usize)];
    let mut left = length;
    while left > 0 {
        let n = buf.len().min(left as usize);
        from.read_exact(&mut buf[..n])?;
        each(&buf[..n])?;
        left -= n as u64;
    }
    Ok(())
}

/// Copies a raw section's `length` stored bytes from `from` to `to`, checking them against the
/// entry's `raw_hash`. `progress` gets the number of bytes of each step.
pub fn copy_raw(
    e: &SectionEntry,
    from: &mut dyn Read,
    to: &mut dyn io::Write,
    progress: &mut dyn FnMut(u64),
) -> Result<(), StreamError> {
    let mut hasher = blake3::Hasher::new();
    for_each_chunk(from, e.stored_length, &mut |chunk| {
        hasher.update(chunk);
        progress(chunk.len() as u64);
        to.write_all(chunk)
    })?;
    Ok(check_hash(e, *hasher.finalize().as_bytes())?)
}

#[cfg(feature = "zstd")]
pub use with_zstd::*;

#[cfg(feature = "zstd")]
mod with_zstd {
    use super::*;
    use std::io::Write;
    use zstd::stream::raw::{Decoder, InBuffer, Operation, OutBuffer};
    use zstd::zstd_safe;

    fn decode_error(e: &SectionEntry, problem: String) -> FormatError {
        FormatError::Decode { kind: kind_name(e.kind), problem }
    }

    /// A `Write` adapter that counts bytes.
    struct Counting<W> {
        inner: W,
        written: u64,
    }

    impl<W: Write> Write for Counting<W> {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            let n = self.inner.write(buf)?;
            self.written += n as u64;
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            self.inner.flush()
        }
    }

    /// Compresses `raw_length` bytes read from `raw` into one zstd frame written to `out` (§8.2):
    /// level `level`, single-threaded, the content size in the frame header, no checksum and no
    /// dictionary id. The input is fed in fixed 1 MiB steps, so the frame depends only on the
    /// bytes, the level and the zstd library version. Returns the frame's length and the BLAKE3
    /// of the raw bytes; `progress` gets the raw bytes of each step.
    pub fn encode_frame(
        raw: &mut dyn Read,
        raw_length: u64,
        level: i32,
        out: &mut dyn Write,
        progress: &mut dyn FnMut(u64),
    ) -> io::Result<(u64, [u8; 32])> {
        if !LEVELS.contains(&level) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("zstd level {level} is outside {}..={}", LEVELS.start(), LEVELS.end()),
            ));
        }
        let mut encoder = zstd::stream::write::Encoder::new(Counting { inner: out, written: 0 }, level)?;
        encoder.set_pledged_src_size(Some(raw_length))?;
        encoder.include_contentsize(true)?;
        encoder.include_checksum(false)?;
        encoder.include_dictid(false)?;
        let mut hasher = blake3::Hasher::new();
        for_each_chunk(raw, raw_length, &mut |chunk| {
            hasher.update(chunk);
            progress(chunk.len() as u64);
            encoder.write_all(chunk)
        })?;
        let counted = encoder.finish()?;
        Ok((counted.written, *hasher.finalize().as_bytes()))
    }

    /// Decodes the zstd section `e`, whose stored bytes are `stored`, into `dst` (which must be
    /// `raw_length` bytes): the stored bytes must be exactly one frame that decodes to exactly
    /// `raw_length` bytes with BLAKE3 `raw_hash`. Writes nothing outside `dst`.
    pub fn decode_frame_into(e: &SectionEntry, stored: &[u8], dst: &mut [u8]) -> Result<(), FormatError> {
        match zstd_safe::find_frame_compressed_size(stored) {
            Ok(n) if n == stored.len() => {}
            Ok(n) => {
                return Err(decode_error(
                    e,
                    format!(
                        "its {} stored bytes hold a {n}-byte zstd frame and {} bytes more; a section is exactly one frame",
                        stored.len(),
                        stored.len() - n
                    ),
                ));
            }
            Err(code) => {
                return Err(decode_error(
                    e,
                    format!("its stored bytes are not one zstd frame ({})", zstd_safe::get_error_name(code)),
                ));
            }
        }
        let mut decompressor = zstd::bulk::Decompressor::new().map_err(|err| decode_error(e, err.to_string()))?;
        let n = decompressor.decompress_to_buffer(stored, dst).map_err(|err| {
            decode_error(e, format!("the zstd frame does not decode into raw_length {} bytes: {err}", e.raw_length))
        })?;
        if n as u64 != e.raw_length {
            return Err(decode_error(e, format!("decodes to {n} bytes, the table says raw_length {}", e.raw_length)));
        }
        check_hash(e, *blake3::hash(dst).as_bytes())
    }

    /// Decodes the zstd section `e` streaming: reads its `stored_length` stored bytes from
    /// `stored`, writes the `raw_length` decoded bytes to `out` and checks them like
    /// [`decode_frame_into`]. Memory is bounded (two 1 MiB buffers and the frame's window, which
    /// zstd limits to 128 MiB) whatever the lengths claim. `progress` gets decoded bytes.
    pub fn decode_frame_stream(
        e: &SectionEntry,
        stored: &mut dyn Read,
        out: &mut dyn Write,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), StreamError> {
        let mut decoder = Decoder::new()?;
        let mut input = vec![0u8; CHUNK.min(e.stored_length as usize)];
        let mut output = vec![0u8; CHUNK];
        let (mut in_pos, mut in_len, mut unread) = (0usize, 0usize, e.stored_length);
        let mut hasher = blake3::Hasher::new();
        let mut decoded = 0u64;
        loop {
            if in_pos == in_len && unread > 0 {
                in_len = input.len().min(unread as usize);
                stored.read_exact(&mut input[..in_len])?;
                unread -= in_len as u64;
                in_pos = 0;
            }
            let mut src = InBuffer::around(&input[in_pos..in_len]);
            let mut dst = OutBuffer::around(&mut output[..]);
            let hint = decoder
                .run(&mut src, &mut dst)
                .map_err(|err| decode_error(e, format!("the zstd frame is corrupt: {err}")))?;
            let (consumed, produced) = (src.pos(), dst.pos());
            in_pos += consumed;
            if decoded + produced as u64 > e.raw_length {
                return Err(decode_error(e, format!("decodes to more than raw_length {} bytes", e.raw_length)).into());
            }
            hasher.update(&output[..produced]);
            out.write_all(&output[..produced])?;
            decoded += produced as u64;
            progress(produced as u64);
            if hint == 0 {
                break; // The frame is complete and fully flushed.
            }
            if consumed == 0 && produced == 0 && in_pos == in_len && unread == 0 {
                return Err(decode_error(e, "its stored bytes end before its zstd frame does".into()).into());
            }
        }
        let trailing = (in_len - in_pos) as u64 + unread;
        if trailing > 0 {
            return Err(decode_error(
                e,
                format!("{trailing} stored bytes follow the end of its zstd frame; a section is exactly one frame"),
            )
            .into());
        }
        if decoded != e.raw_length {
            return Err(decode_error(
                e,
                format!("decodes to {decoded} bytes, the table says raw_length {}", e.raw_length),
            )
            .into());
        }
        Ok(check_hash(e, *hasher.finalize().as_bytes())?)
    }

    /// Fields at least this large (decoded) are decoded on several threads.
    const PARALLEL_BYTES: u64 = 8 << 20;

    /// Decodes a packed (or raw) field held in memory into one 64-byte-aligned buffer laid out as
    /// the raw field ([`unpacked_layout`]), checking every section's length and hash. The first
    /// faulty section in table order is reported, whatever the thread count.
    ///
    /// Memory: the raw field's size, which the table claims; each compressed section's claim is
    /// bounded by [`MAX_ZSTD_EXPANSION`] times its stored bytes (checked at [`parse_head`]), the
    /// total by `max_bytes` if given ([`FormatError::UnpackedTooLarge`]); the buffer is allocated
    /// zeroed and lazily, so a claim that the frames do not back costs address space only, and an
    /// allocation failure is [`FormatError::OutOfMemory`].
    ///
    /// Time: linear in the raw size. Fields of 8 MiB and more are decoded on scoped threads, one
    /// per available core at most, each decoding whole sections (biggest first).
    pub fn unpack_in_memory(bytes: &[u8], max_bytes: Option<u64>) -> Result<Unpacked, FormatError> {
        let (header, table) = parse_head(bytes, bytes.len() as u64)?;
        let (raw_header, raw_table) = unpacked_layout(&header, &table)?;
        if let Some(limit) = max_bytes
            && raw_header.file_length > limit
        {
            return Err(FormatError::UnpackedTooLarge { bytes: raw_header.file_length, limit });
        }
        let mut buf = crate::AlignedBytes::zeroed(raw_header.file_length)?;
        let head = head_bytes(&raw_header, &raw_table);
        let (out_head, mut rest) = buf.as_bytes_mut().split_at_mut(head.len());
        out_head.copy_from_slice(&head);

        // One job per section: its index, entry, stored bytes and (disjoint) destination. In
        // bounds: parse_head checked the stored ranges, lay_out computed the raw ones.
        let mut jobs = Vec::with_capacity(table.len());
        let mut at = head.len() as u64;
        for (index, (e, r)) in table.iter().zip(&raw_table).enumerate() {
            let (_padding, tail) = std::mem::take(&mut rest).split_at_mut((r.offset - at) as usize);
            let (dst, tail) = tail.split_at_mut(r.raw_length as usize);
            rest = tail;
            at = r.offset + r.raw_length;
            jobs.push((index, e, &bytes[e.offset as usize..(e.offset + e.stored_length) as usize], dst));
        }
        let decode = |(index, e, stored, dst): (usize, &SectionEntry, &[u8], &mut [u8])| {
            let result = if e.codec == codec::RAW {
                dst.copy_from_slice(stored);
                check_hash(e, *blake3::hash(dst).as_bytes())
            } else {
                decode_frame_into(e, stored, dst)
            };
            result.err().map(|err| (index, err))
        };
        let threads = if raw_header.file_length < PARALLEL_BYTES {
            1
        } else {
            std::thread::available_parallelism().map_or(1, |n| n.get()).min(jobs.len())
        };
        let mut errors: Vec<(usize, FormatError)> = if threads <= 1 {
            jobs.into_iter().filter_map(decode).collect()
        } else {
            jobs.sort_by_key(|job| std::cmp::Reverse(job.1.raw_length));
            let queue = std::sync::Mutex::new(jobs.into_iter());
            let next = || queue.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).next();
            std::thread::scope(|scope| {
                let workers: Vec<_> = (0..threads)
                    .map(|_| scope.spawn(|| std::iter::from_fn(next).filter_map(decode).collect::<Vec<_>>()))
                    .collect();
                workers
                    .into_iter()
                    .flat_map(|w| w.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
                    .collect()
            })
        };
        errors.sort_by_key(|(index, _)| *index);
        match errors.into_iter().next() {
            Some((_, err)) => Err(err),
            None => Ok(Unpacked { bytes: buf, packed: PackedLayout { header, table } }),
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        fn entry(raw: &[u8]) -> SectionEntry {
            SectionEntry {
                kind: 999,
                codec: codec::ZSTD,
                offset: 0,
                stored_length: 0,
                raw_length: raw.len() as u64,
                element_size: 1,
                reserved: 0,
                raw_hash: *blake3::hash(raw).as_bytes(),
            }
        }

        fn encode(raw: &[u8], level: i32) -> Vec<u8> {
            let mut out = Vec::new();
            let (n, hash) = encode_frame(&mut &raw[..], raw.len() as u64, level, &mut out, &mut |_| {}).unwrap();
            assert_eq!(n, out.len() as u64);
            assert_eq!(hash, *blake3::hash(raw).as_bytes());
            out
        }

        fn sample(len: usize) -> Vec<u8> {
            (0..len as u32).flat_map(|i| (i / 7 % 251).to_le_bytes()).take(len).collect()
        }

        #[test]
        fn frames_round_trip_in_memory_and_streaming() {
            for len in [0, 1, 100, 3 * CHUNK + 5] {
                let raw = sample(len);
                let frame = encode(&raw, 3);
                let mut e = entry(&raw);
                e.stored_length = frame.len() as u64;
                let mut dst = vec![0u8; len];
                decode_frame_into(&e, &frame, &mut dst).unwrap();
                assert_eq!(dst, raw);
                let mut streamed = Vec::new();
                decode_frame_stream(&e, &mut &frame[..], &mut streamed, &mut |_| {}).unwrap();
                assert_eq!(streamed, raw);
            }
        }

        /// The bound that `parse_head` enforces holds for the most compressible input at every level.
        #[test]
        fn no_frame_beats_the_expansion_bound() {
            let zeros = vec![0u8; 16 << 20];
            for level in [1, 3, 9, 19] {
                let frame = encode(&zeros, level);
                assert!((zeros.len() as u64) < frame.len() as u64 * MAX_ZSTD_EXPANSION, "level {level}");
            }
        }

        #[test]
        fn damaged_frames_are_named_errors_in_both_decoders() {
            let raw = sample(200_000);
            let frame = encode(&raw, 3);
            let good = SectionEntry { stored_length: frame.len() as u64, ..entry(&raw) };
            let mut flipped = frame.clone();
            flipped[frame.len() / 2] ^= 0x55;
            let cases: Vec<(SectionEntry, Vec<u8>)> = vec![
                (good, flipped),
                (SectionEntry { stored_length: frame.len() as u64 - 10, ..good }, frame[..frame.len() - 10].to_vec()),
                (SectionEntry { stored_length: frame.len() as u64 + 3, ..good }, [&frame[..], &[0, 0, 0]].concat()),
                (SectionEntry { raw_length: good.raw_length - 1, ..good }, frame.clone()),
                (SectionEntry { raw_length: good.raw_length + 1, ..good }, frame.clone()),
                (SectionEntry { raw_hash: [7; 32], ..good }, frame.clone()),
                (SectionEntry { stored_length: 0, ..good }, Vec::new()),
            ];
            for (i, (e, stored)) in cases.iter().enumerate() {
                let mut dst = vec![0u8; e.raw_length as usize];
                let err = decode_frame_into(e, stored, &mut dst).expect_err(&format!("case {i} decoded in memory"));
                assert!(err.to_string().contains("unknown kind 999"), "case {i}: {err}");
                let err = decode_frame_stream(e, &mut &stored[..], &mut Vec::new(), &mut |_| {})
                    .expect_err(&format!("case {i} decoded streaming"));
                assert!(err.to_string().contains("unknown kind 999"), "case {i}: {err}");
            }
        }
    }
}
