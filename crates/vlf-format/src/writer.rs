//! The writer: lays out every section before writing a byte (so the table, with every section's
//! hash, can come first), then streams header, table and sections to any `Write` in one pass.
//!
//! Sections come either as bytes in memory or as a reader (a spill file) whose length and
//! BLAKE3 the caller already knows, so a field of many GiB is written without holding it in
//! memory. Atomic replacement of the output path is the caller's business (`vlf-bake` writes a
//! temporary file in the output directory and renames it).

use crate::layout::*;
use crate::reader::content_hash;
use std::io::{self, Read, Write};

/// Where a section's bytes come from.
pub enum Payload<'a> {
    /// Bytes in memory; the writer hashes them.
    Bytes(&'a [u8]),
    /// `length` bytes to be read from `reader`, whose BLAKE3 is `raw_hash` (computed by the
    /// caller while producing them, for example with [`HashingWriter`]). The writer checks the
    /// length it copies.
    Stream { reader: &'a mut dyn Read, length: u64, raw_hash: [u8; 32] },
}

/// One section to write.
pub struct SectionPayload<'a> {
    pub kind: u32,
    pub element_size: u32,
    pub payload: Payload<'a>,
}

impl<'a> SectionPayload<'a> {
    pub fn bytes(kind: SectionKind, bytes: &'a [u8]) -> Self {
        SectionPayload { kind: kind as u32, element_size: kind.element_size(), payload: Payload::Bytes(bytes) }
    }

    fn length(&self) -> u64 {
        match &self.payload {
            Payload::Bytes(b) => b.len() as u64,
            Payload::Stream { length, .. } => *length,
        }
    }
}

/// Offsets of a laid-out file, before any byte is written.
pub fn layout(lengths: &[u64]) -> (Vec<u64>, u64) {
    let mut pos = (HEADER_SIZE + TABLE_ENTRY_SIZE * lengths.len()) as u64;
    let mut offsets = Vec::with_capacity(lengths.len());
    for &len in lengths {
        pos = pos.next_multiple_of(SECTION_ALIGN);
        offsets.push(pos);
        pos += len;
    }
    (offsets, pos)
}

/// Writes a complete field to `out` and returns its header. Sections are written raw, in the
/// order given, each at the next multiple of 64.
pub fn write_field<W: Write>(
    out: &mut W,
    input_hash: [u8; 32],
    sections: &mut [SectionPayload<'_>],
) -> io::Result<Header> {
    if sections.len() > MAX_SECTIONS as usize {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, "too many sections"));
    }
    let lengths: Vec<u64> = sections.iter().map(|s| s.length()).collect();
    let (offsets, file_length) = layout(&lengths);

    let table: Vec<SectionEntry> = sections
        .iter()
        .zip(&offsets)
        .map(|(s, &offset)| SectionEntry {
            kind: s.kind,
            codec: codec::RAW,
            offset,
            stored_length: s.length(),
            raw_length: s.length(),
            element_size: s.element_size,
            reserved: 0,
            raw_hash: match &s.payload {
                Payload::Bytes(b) => *blake3::hash(b).as_bytes(),
                Payload::Stream { raw_hash, .. } => *raw_hash,
            },
        })
        .collect();
    let mut header = Header {
        magic: MAGIC,
        version_major: VERSION_MAJOR,
        version_minor: VERSION_MINOR,
        header_size: HEADER_SIZE as u32,
        file_length,
        table_offset: HEADER_SIZE as u64,
        section_count: sections.len() as u32,
        table_entry_size: TABLE_ENTRY_SIZE as u32,
        flags: 0,
        reserved0: 0,
        content_hash: [0; 32],
        input_hash,
        reserved1: [0; 16],
    };
    let mut head = Vec::with_capacity(HEADER_SIZE + TABLE_ENTRY_SIZE * table.len());
    head.extend_from_slice(bytemuck::bytes_of(&header));
    head.extend_from_slice(bytemuck::cast_slice(&table));
    header.content_hash = content_hash(&head);
    head[CONTENT_HASH_RANGE].copy_from_slice(&header.content_hash);

    out.write_all(&head)?;
    let mut pos = head.len() as u64;
    let zeros = [0u8; SECTION_ALIGN as usize];
    for (section, &offset) in sections.iter_mut().zip(&offsets) {
        out.write_all(&zeros[..(offset - pos) as usize])?;
        match &mut section.payload {
            Payload::Bytes(b) => out.write_all(b)?,
            Payload::Stream { reader, length, .. } => {
                let copied = io::copy(&mut reader.take(*length), out)?;
                if copied != *length {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        format!("section {} stream ended after {copied} of {length} bytes", kind_name(section.kind)),
                    ));
                }
            }
        }
        pos = offset + section.length();
    }
    debug_assert_eq!(pos, file_length);
    Ok(header)
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
