//! The writer: a field file written in place, each byte once.
//!
//! [`FieldFile`] reserves the header and section table at the start of the file, then places
//! sections one after another at 64-byte boundaries, in the order they are added (which is the
//! table's order, sorted by offset as the spec requires). A section is either appended from bytes
//! in memory, reserved with a known length and filled later (possibly while other sections are
//! written), or streamed with a length known only when it ends. Every section is hashed as it is
//! written; [`FieldFile::finish`] writes the table and the header with the content hash over both
//! (§3.1), which is why sections may be written in any order.
//!
//! Every byte reaches the file in a write of a whole [`WRITE_CHUNK`] (2 MiB) aligned on the file,
//! except at its end: sections written in pieces and at different places are gathered into their
//! chunks first (`Chunks`). Where the file system caches files in large folios (Linux ext4 from
//! 6.16, XFS), a file written this way sits in the page cache in huge-page-sized pieces, which a
//! reader's memory map then maps with huge pages: a query touching a large field takes far fewer
//! TLB misses (`docs/benchmarks/where-the-time-goes.md`). Elsewhere it is ordinary buffering.
//!
//! Atomic replacement of the output path is the caller's business (`vlf-bake` writes into a
//! temporary file in the output directory, syncs it and renames it).

use crate::layout::*;
use crate::reader::content_hash;
use crate::section::*;
use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::{self, Read, Write};
use std::sync::{Arc, Mutex, MutexGuard};

/// The size and alignment of the writes a [`FieldFile`] and an [`AlignedWriter`] make: 2 MiB, the
/// huge page of x86-64 and of aarch64 with 4 KiB pages.
pub const WRITE_CHUNK: usize = 2 << 20;

/// Writes all of `buf` at `offset` without moving a shared cursor.
fn write_all_at(file: &File, buf: &[u8], offset: u64) -> io::Result<()> {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileExt::write_all_at(file, buf, offset)
    }
    #[cfg(windows)]
    {
        let (mut buf, mut offset) = (buf, offset);
        while !buf.is_empty() {
            let n = std::os::windows::fs::FileExt::seek_write(file, buf, offset)?;
            if n == 0 {
                return Err(io::ErrorKind::WriteZero.into());
            }
            buf = &buf[n..];
            offset += n as u64;
        }
        Ok(())
    }
}

/// The chunks of a file being written at many places: each chunk's bytes are gathered in memory
/// until all of it has been written, then written at once. Each byte of the file is written once
/// (gaps between sections as zeros), so a chunk completes when its last byte arrives; what is
/// still gathered when the file ends is written by [`Chunks::flush`]. At most one chunk per place
/// being written (an open section, a gap) is held at a time. (Should a byte be written twice, its
/// chunk may be written early; later writes to it then go straight to the file, so the file's
/// bytes are right whatever the order.)
struct Chunks {
    file: File,
    /// Chunk index to its bytes and how many of them were written.
    gathering: BTreeMap<u64, (Box<[u8]>, usize)>,
    /// The chunks already written to the file.
    written: BTreeSet<u64>,
}

impl Chunks {
    /// Writes `buf` at `offset`.
    fn write_at(&mut self, mut buf: &[u8], mut offset: u64) -> io::Result<()> {
        let chunk = WRITE_CHUNK as u64;
        while !buf.is_empty() {
            let (index, within) = (offset / chunk, (offset % chunk) as usize);
            let n = buf.len().min(WRITE_CHUNK - within);
            let (part, rest) = buf.split_at(n);
            if n == WRITE_CHUNK || self.written.contains(&index) {
                // A whole chunk at once (no copy; it replaces anything gathered for it), or a
                // chunk already written.
                self.gathering.remove(&index);
                write_all_at(&self.file, part, offset)?;
                self.written.insert(index);
            } else {
                let (bytes, filled) =
                    self.gathering.entry(index).or_insert_with(|| (vec![0; WRITE_CHUNK].into_boxed_slice(), 0));
                bytes[within..within + n].copy_from_slice(part);
                *filled += n;
                if *filled >= WRITE_CHUNK {
                    let (bytes, _) = self.gathering.remove(&index).expect("the chunk being gathered");
                    write_all_at(&self.file, &bytes, index * chunk)?;
                    self.written.insert(index);
                }
            }
            (buf, offset) = (rest, offset + n as u64);
        }
        Ok(())
    }

    /// Writes what is still gathered, up to the file's end `end`.
    fn flush(&mut self, end: u64) -> io::Result<()> {
        for (index, (bytes, _)) in std::mem::take(&mut self.gathering) {
            let at = index * WRITE_CHUNK as u64;
            let len = end.saturating_sub(at).min(WRITE_CHUNK as u64) as usize;
            write_all_at(&self.file, &bytes[..len], at)?;
            self.written.insert(index);
        }
        Ok(())
    }
}

/// The chunks of one file, shared by the [`FieldFile`] and its [`SectionWriter`]s.
#[derive(Clone)]
struct SharedChunks(Arc<Mutex<Chunks>>);

impl SharedChunks {
    fn lock(&self) -> MutexGuard<'_, Chunks> {
        // A writer that panicked mid-copy leaves a chunk with some bytes unwritten: the file is
        // abandoned by its caller anyway (a bake writes a temporary file and renames it only once
        // it is finished).
        self.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn write_at(&self, buf: &[u8], offset: u64) -> io::Result<()> {
        self.lock().write_at(buf, offset)
    }
}

/// A field file being written. See the module documentation.
pub struct FieldFile {
    file: File,
    chunks: SharedChunks,
    magic: [u8; 8],
    table: Vec<SectionEntry>,
    /// Sections handed out as writers and not yet finished (their table index).
    open: Vec<usize>,
    capacity: usize,
    end: u64,
}

/// A section being written sequentially at its own offset. Buffered; hashes what it writes.
pub struct SectionWriter {
    chunks: SharedChunks,
    index: usize,
    start: u64,
    /// `Some(n)` for a reserved section that must be exactly `n` bytes long.
    reserved: Option<u64>,
    written: u64,
    buf: Vec<u8>,
    hasher: blake3::Hasher,
}

const BUFFER: usize = 1 << 20;

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

impl FieldFile {
    /// Starts a field in `file` (empty, writable) that will hold `sections` sections.
    pub fn create(file: File, sections: usize) -> io::Result<FieldFile> {
        FieldFile::create_with_magic(file, sections, MAGIC)
    }

    /// Starts a file of another type built on the field's container (a shard,
    /// [`SHARD_MAGIC`]): the same layout with `magic` in the header.
    pub fn create_with_magic(file: File, sections: usize, magic: [u8; 8]) -> io::Result<FieldFile> {
        if sections > MAX_SECTIONS as usize {
            return Err(invalid(format!("{sections} sections exceed the limit of {MAX_SECTIONS}")));
        }
        file.set_len(0)?;
        let end = (HEADER_SIZE + TABLE_ENTRY_SIZE * sections) as u64;
        let chunks = SharedChunks(Arc::new(Mutex::new(Chunks {
            file: file.try_clone()?,
            gathering: BTreeMap::new(),
            written: BTreeSet::new(),
        })));
        Ok(FieldFile {
            file,
            chunks,
            magic,
            table: Vec::with_capacity(sections),
            open: Vec::new(),
            capacity: sections,
            end,
        })
    }

    fn place(&mut self, kind: u32, element_size: u32, length: u64) -> io::Result<(usize, u64)> {
        if self.table.len() == self.capacity {
            return Err(invalid(format!("more sections than the {} announced", self.capacity)));
        }
        if self.open.iter().any(|&i| self.table[i].stored_length == u64::MAX) {
            return Err(invalid("a streamed section is still open; finish it before adding sections".into()));
        }
        let offset = self.end.next_multiple_of(SECTION_ALIGN);
        // The padding before the section is written too (as zeros), so that every chunk of the
        // file completes.
        self.chunks.write_at(&[0; SECTION_ALIGN as usize][..(offset - self.end) as usize], self.end)?;
        self.table.push(SectionEntry {
            kind,
            codec: codec::RAW,
            offset,
            stored_length: length,
            raw_length: length,
            element_size,
            reserved: 0,
            raw_hash: [0; 32],
        });
        if length != u64::MAX {
            self.end = offset + length;
        }
        Ok((self.table.len() - 1, offset))
    }

    /// Appends a section from bytes in memory.
    pub fn append(&mut self, kind: SectionKind, bytes: &[u8]) -> io::Result<()> {
        self.append_kind(kind as u32, kind.element_size(), bytes)
    }

    /// Appends a section of any kind number and element size from bytes in memory (a section this
    /// crate does not know, carried over from another file, or a shard's SHARD record).
    pub fn append_kind(&mut self, kind: u32, element_size: u32, bytes: &[u8]) -> io::Result<()> {
        if element_size == 0 || !(bytes.len() as u64).is_multiple_of(element_size as u64) {
            return Err(invalid(format!("section {} is not a whole number of elements", kind_name(kind))));
        }
        let (index, offset) = self.place(kind, element_size, bytes.len() as u64)?;
        self.chunks.write_at(bytes, offset)?;
        self.table[index].raw_hash = *blake3::hash(bytes).as_bytes();
        Ok(())
    }

    /// Appends a section of `length` bytes read from `reader`, whose BLAKE3 is `raw_hash`
    /// (computed while it was produced, for example by a spill file's [`SectionWriter`]-like
    /// hashing). Copies through a buffer; the length is checked.
    pub fn append_from(
        &mut self,
        kind: SectionKind,
        reader: &mut dyn Read,
        length: u64,
        raw_hash: [u8; 32],
    ) -> io::Result<()> {
        let (index, offset) = self.place(kind as u32, kind.element_size(), length)?;
        let mut buf = vec![0u8; BUFFER.min(length as usize).max(1)];
        let mut done = 0u64;
        while done < length {
            let want = buf.len().min((length - done) as usize);
            reader.read_exact(&mut buf[..want])?;
            self.chunks.write_at(&buf[..want], offset + done)?;
            done += want as u64;
        }
        self.table[index].raw_hash = raw_hash;
        Ok(())
    }

    /// Reserves a section of exactly `length` bytes, to be filled through the returned writer
    /// (while other sections are added) and closed with [`FieldFile::finish_section`].
    pub fn reserve(&mut self, kind: SectionKind, length: u64) -> io::Result<SectionWriter> {
        self.reserve_kind(kind as u32, kind.element_size(), length)
    }

    /// [`FieldFile::reserve`] for any kind number and element size.
    pub fn reserve_kind(&mut self, kind: u32, element_size: u32, length: u64) -> io::Result<SectionWriter> {
        if element_size == 0 {
            return Err(invalid(format!("section {} has element size 0", kind_name(kind))));
        }
        let (index, offset) = self.place(kind, element_size, length)?;
        self.open.push(index);
        self.writer(index, offset, Some(length))
    }

    /// Starts a section whose length is known only when it ends. Until it is finished with
    /// [`FieldFile::finish_section`], no other section can be added (reserved ones can be filled).
    pub fn stream(&mut self, kind: SectionKind) -> io::Result<SectionWriter> {
        let (index, offset) = self.place(kind as u32, kind.element_size(), u64::MAX)?;
        self.open.push(index);
        self.writer(index, offset, None)
    }

    fn writer(&self, index: usize, start: u64, reserved: Option<u64>) -> io::Result<SectionWriter> {
        Ok(SectionWriter {
            chunks: self.chunks.clone(),
            index,
            start,
            reserved,
            written: 0,
            buf: Vec::with_capacity(BUFFER),
            hasher: blake3::Hasher::new(),
        })
    }

    /// Closes a section opened with [`FieldFile::reserve`] or [`FieldFile::stream`] and returns the
    /// BLAKE3 of the bytes written to it.
    pub fn finish_section(&mut self, mut w: SectionWriter) -> io::Result<[u8; 32]> {
        w.flush_buf()?;
        let pos = self.open.iter().position(|&i| i == w.index).ok_or_else(|| invalid("section is not open".into()))?;
        self.open.swap_remove(pos);
        let e = &mut self.table[w.index];
        if let Some(len) = w.reserved {
            if w.written != len {
                return Err(invalid(format!(
                    "section {} reserved {len} bytes but {} were written",
                    kind_name(e.kind),
                    w.written
                )));
            }
        } else {
            e.stored_length = w.written;
            e.raw_length = w.written;
            self.end = w.start + w.written;
        }
        if !e.raw_length.is_multiple_of(e.element_size as u64) {
            return Err(invalid(format!("section {} is not a whole number of elements", kind_name(e.kind))));
        }
        e.raw_hash = *w.hasher.finalize().as_bytes();
        Ok(e.raw_hash)
    }

    /// Writes the section table and the header (with the content hash and `input_hash`) and
    /// returns the file and the header. Every announced section must have been added and closed.
    pub fn finish(self, input_hash: [u8; 32]) -> io::Result<(File, Header)> {
        if !self.open.is_empty() || self.table.len() != self.capacity {
            return Err(invalid(format!(
                "{} of {} sections added, {} still open",
                self.table.len(),
                self.capacity,
                self.open.len()
            )));
        }
        // Pad the end so the file ends exactly where its last section does (already true) and
        // make sure the length is right even if the last section was empty.
        self.file.set_len(self.end)?;
        let mut header = Header {
            magic: self.magic,
            version_major: VERSION_MAJOR,
            version_minor: VERSION_MINOR,
            header_size: HEADER_SIZE as u32,
            file_length: self.end,
            table_offset: HEADER_SIZE as u64,
            section_count: self.table.len() as u32,
            table_entry_size: TABLE_ENTRY_SIZE as u32,
            flags: 0,
            reserved0: 0,
            content_hash: [0; 32],
            input_hash,
            reserved1: [0; 16],
        };
        let mut head = Vec::with_capacity(HEADER_SIZE + TABLE_ENTRY_SIZE * self.table.len());
        head.extend_from_slice(bytemuck::bytes_of(&header));
        head.extend_from_slice(bytemuck::cast_slice(&self.table));
        header.content_hash = content_hash(&head);
        head[CONTENT_HASH_RANGE].copy_from_slice(&header.content_hash);
        let mut chunks = self.chunks.lock();
        chunks.write_at(&head, 0)?;
        chunks.flush(self.end)?;
        drop(chunks);
        Ok((self.file, header))
    }
}

impl SectionWriter {
    fn flush_buf(&mut self) -> io::Result<()> {
        if !self.buf.is_empty() {
            let at = self.start + self.written - self.buf.len() as u64;
            self.chunks.write_at(&self.buf, at)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// Bytes written so far.
    pub fn written(&self) -> u64 {
        self.written
    }
}

impl Write for SectionWriter {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        if let Some(len) = self.reserved
            && self.written + data.len() as u64 > len
        {
            return Err(invalid(format!("write past the end of a {len}-byte reserved section")));
        }
        // `written` counts buffered bytes too; the buffer holds the last `buf.len()` of them.
        if self.buf.len() + data.len() > BUFFER {
            self.flush_buf()?;
        }
        self.hasher.update(data);
        if data.len() >= BUFFER {
            self.chunks.write_at(data, self.start + self.written)?;
        } else {
            self.buf.extend_from_slice(data);
        }
        self.written += data.len() as u64;
        Ok(data.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.flush_buf()
    }
}

/// A sequential writer that hands its inner writer whole [`WRITE_CHUNK`]s (2 MiB), each starting
/// where the previous one ended: written from the start of a file, every write is a whole,
/// aligned huge page (see the module documentation), except the last. For copying fields
/// (`vlf-bake unpack`, the bake cache) so that the copy maps with huge pages too.
///
/// [`Write::flush`] writes what is buffered, as it must: a writer flushed before its end loses the
/// alignment from there on (not the bytes). [`AlignedWriter::finish`] flushes and returns the
/// inner writer.
pub struct AlignedWriter<W: Write> {
    inner: W,
    buf: Vec<u8>,
}

impl<W: Write> AlignedWriter<W> {
    pub fn new(inner: W) -> Self {
        AlignedWriter { inner, buf: Vec::with_capacity(WRITE_CHUNK) }
    }

    /// Writes what is buffered and returns the inner writer, flushed.
    pub fn finish(mut self) -> io::Result<W> {
        self.flush()?;
        let AlignedWriter { inner, .. } = self;
        Ok(inner)
    }
}

impl<W: Write> Write for AlignedWriter<W> {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        // A full chunk goes out before more is taken, so that an error takes none of `data`.
        if self.buf.len() == WRITE_CHUNK {
            self.inner.write_all(&self.buf)?;
            self.buf.clear();
        }
        let n = data.len().min(WRITE_CHUNK - self.buf.len());
        self.buf.extend_from_slice(&data[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        if !self.buf.is_empty() {
            self.inner.write_all(&self.buf)?;
            self.buf.clear();
        }
        self.inner.flush()
    }
}

/// A `Write` adapter that hashes and counts what passes through, for spilling a section to a
/// temporary file while computing its table entry.
pub struct HashingWriter<W> {
    inner: W,
    hasher: blake3::Hasher,
    written: u64,
}

impl<W: Write> HashingWriter<W> {
    pub fn new(inner: W) -> Self {
        HashingWriter { inner, hasher: blake3::Hasher::new(), written: 0 }
    }

    /// The inner writer, the number of bytes written and their BLAKE3.
    pub fn finish(mut self) -> io::Result<(W, u64, [u8; 32])> {
        self.inner.flush()?;
        Ok((self.inner, self.written, *self.hasher.finalize().as_bytes()))
    }
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.written += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sections added in any mix of append, reserve and stream read back with the right bytes,
    /// hashes and layout; misuse is an error, not a corrupt file.
    #[test]
    fn a_mixed_write_reads_back() {
        let tmp = std::env::temp_dir().join(format!("vlf-writer-test-{}", std::process::id()));
        let file = File::options().read(true).write(true).create(true).truncate(true).open(&tmp).unwrap();
        let mut f = FieldFile::create(file, 3).unwrap();
        f.append(SectionKind::Strings, b"hello").unwrap();
        let mut reserved = f.reserve(SectionKind::Leaves, 8).unwrap();
        let mut streamed = f.stream(SectionKind::Tiles).unwrap();
        assert!(f.append(SectionKind::Scene, &[0; 128]).is_err(), "no section may follow an open stream");
        streamed.write_all(&[1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0]).unwrap();
        reserved.write_all(&[9, 0, 0, 0]).unwrap();
        reserved.write_all(&[8, 0, 0, 0]).unwrap();
        assert!(reserved.write_all(&[0]).is_err(), "a reserved section cannot overflow");
        f.finish_section(streamed).unwrap();
        f.finish_section(reserved).unwrap();
        let (_, header) = f.finish([7; 32]).unwrap();
        let bytes = std::fs::read(&tmp).unwrap();
        std::fs::remove_file(&tmp).unwrap();
        assert_eq!(header.file_length, bytes.len() as u64);
        let (h, table) = crate::reader::read_header_and_table(&bytes).unwrap();
        assert_eq!(h.input_hash, [7; 32]);
        let kinds: Vec<u32> = table.iter().map(|e| e.kind).collect();
        assert_eq!(kinds, [SectionKind::Strings as u32, SectionKind::Leaves as u32, SectionKind::Tiles as u32]);
        for e in table {
            let raw = &bytes[e.offset as usize..(e.offset + e.stored_length) as usize];
            assert_eq!(*blake3::hash(raw).as_bytes(), e.raw_hash);
        }
        assert_eq!(&bytes[table[1].offset as usize..][..8], &[9, 0, 0, 0, 8, 0, 0, 0]);
    }

    /// Sections larger than a chunk, written in odd pieces and interleaved (a reserved section
    /// filled while another streams), read back byte for byte: the chunks gather every byte.
    #[test]
    fn sections_across_chunks_read_back() {
        let dir = std::env::temp_dir().join(format!("vlf-writer-chunks-{}", std::process::id()));
        let file = File::options().read(true).write(true).create(true).truncate(true).open(&dir).unwrap();
        let pattern = |seed: u8, len: usize| -> Vec<u8> {
            (0..len).map(|i| (i as u32).wrapping_mul(2_654_435_761).to_le_bytes()[3] ^ seed).collect()
        };
        let (a, b, c) =
            (pattern(1, 3 * WRITE_CHUNK + 5), pattern(2, 5 * WRITE_CHUNK / 2 + 8), pattern(3, 4 * WRITE_CHUNK + 76));
        let mut f = FieldFile::create(file, 3).unwrap();
        f.append(SectionKind::Strings, &a).unwrap();
        let mut reserved = f.reserve(SectionKind::Leaves, b.len() as u64).unwrap();
        let mut streamed = f.stream(SectionKind::Tiles).unwrap();
        let (mut rb, mut rc) = (&b[..], &c[..]);
        while !rb.is_empty() || !rc.is_empty() {
            let (nb, nc) = (rb.len().min(333_333 * 8), rc.len().min(1_234_567));
            reserved.write_all(&rb[..nb]).unwrap();
            streamed.write_all(&rc[..nc]).unwrap();
            (rb, rc) = (&rb[nb..], &rc[nc..]);
        }
        f.finish_section(streamed).unwrap();
        f.finish_section(reserved).unwrap();
        let (_, header) = f.finish([9; 32]).unwrap();
        let bytes = std::fs::read(&dir).unwrap();
        std::fs::remove_file(&dir).unwrap();
        assert_eq!(header.file_length, bytes.len() as u64);
        let (_, table) = crate::reader::read_header_and_table(&bytes).unwrap();
        for (e, want) in table.iter().zip([&a, &b, &c]) {
            assert_eq!(&bytes[e.offset as usize..(e.offset + e.stored_length) as usize], &want[..]);
            assert_eq!(*blake3::hash(want).as_bytes(), e.raw_hash);
        }
        // The padding between sections is zero.
        for w in table.windows(2) {
            assert!(bytes[(w[0].offset + w[0].stored_length) as usize..w[1].offset as usize].iter().all(|&x| x == 0));
        }
    }

    /// An aligned writer hands on whole chunks, the last one short, and every byte in order.
    #[test]
    fn aligned_writer_writes_whole_chunks() {
        struct Record(Vec<u8>, Vec<usize>);
        impl Write for Record {
            fn write(&mut self, b: &[u8]) -> io::Result<usize> {
                self.0.extend_from_slice(b);
                self.1.push(b.len());
                Ok(b.len())
            }
            fn flush(&mut self) -> io::Result<()> {
                Ok(())
            }
        }
        let data: Vec<u8> = (0..2 * WRITE_CHUNK + 12_345).map(|i| (i % 251) as u8).collect();
        let mut w = AlignedWriter::new(Record(Vec::new(), Vec::new()));
        for piece in data.chunks(100_000) {
            w.write_all(piece).unwrap();
        }
        let Record(out, writes) = w.finish().unwrap();
        assert_eq!(out, data);
        assert_eq!(writes, [WRITE_CHUNK, WRITE_CHUNK, 12_345]);
    }
}
