//! The zero-copy reader: validates the header and section table once (time independent of the
//! file size) and hands out typed slices that borrow the file bytes.

use crate::error::{FormatError, hex};
use crate::layout::*;
use crate::section::*;
use bytemuck::Pod;

/// A validated field: typed views of every section, borrowed from the file bytes.
///
/// Construction checks the structure of §7 of `formats/vlf.md` and nothing that depends on the
/// size of the payload. Values *inside* the payload (offsets, ids) are not checked here: use them
/// with bounds-checked access, or run [`crate::verify::verify`] once.
#[derive(Clone, Copy, Debug)]
#[deny(missing_docs)]
pub struct FieldReader<'a> {
    /// The whole file.
    pub bytes: &'a [u8],
    /// The header (§3).
    pub header: &'a Header,
    /// The section table (§4), one entry per section, sorted by offset.
    pub table: &'a [SectionEntry],
    /// SCENE: bounding sphere, bounds and counts.
    pub scene: &'a SceneRecord,
    /// PARAMS: lattice size, tile resolution, BSP policy, margin.
    pub params: &'a ParamsRecord,
    /// STATISTICS: what the baker measured, for `dump`.
    pub statistics: &'a StatisticsRecord,
    /// DIRECTIONS (§5.3): the `l` stored unit directions, `(x, y, z, 0)`.
    pub directions: &'a [[f32; 4]],
    /// ROTATIONS (§5.4): per direction, the row-major rotation into its canonical frame.
    pub rotations: &'a [[f64; 9]],
    /// LOOKUP (§5.3): per lattice cell, `(2N + 1)²` of them, a direction index with a flip bit,
    /// or `LOOKUP_NONE`.
    pub lookup: &'a [u32],
    /// BEAMS (§5.5): per direction, where its leaf bounds and triangle ids start.
    pub beams: &'a [BeamRecord],
    /// TILES (§5.6): the `l · n²` tiles, direction by direction, row by row: where each tile's
    /// block starts in its direction's LEAVES, or [`EMPTY_TILE`].
    pub tiles: &'a [TileEntry],
    /// LEAVES (§5.6): the tile blocks of every direction ([`crate::block`]), in 8-byte words.
    pub leaves: &'a [LeafWord],
    /// TRIANGLES (§5.7): the vertices of every triangle relative to SCENE's centre, in id order.
    pub triangles: &'a [TriangleRecord],
    /// PROVENANCE (§5.8): per triangle, its source and its index within it.
    pub provenance: &'a [ProvenanceRecord],
    /// SOURCES (§5.8): the objects, groups or mesh primitives triangles came from.
    pub sources: &'a [SourceRecord],
    /// INPUTS (§5.8): the input files.
    pub inputs: &'a [InputRecord],
    /// STRINGS (§5.8): the UTF-8 names that SOURCES and INPUTS refer to.
    pub strings: &'a [u8],
    /// MATERIALS (§5.10); empty if the file has none (every 1.0 file).
    pub materials: &'a [MaterialRecord],
    /// CAMERAS (§5.11); empty if the file has none.
    pub cameras: &'a [CameraRecord],
    /// LIGHTS (§5.12); empty if the file has none.
    pub lights: &'a [LightRecord],
    /// DUPLICATES (§5.13); empty if the file has none.
    pub duplicates: &'a [DuplicateRecord],
}

/// The header and table checks of §7, without casting any section. Used by [`FieldReader::new`]
/// and by tools that must describe a file whose sections cannot be cast (a packed field).
pub fn read_header_and_table(bytes: &[u8]) -> Result<(&Header, &[SectionEntry]), FormatError> {
    let len = bytes.len() as u64;
    let header = check_header(bytes, len, &MAGIC)?;
    let table_end = HEADER_SIZE + header.section_count as usize * TABLE_ENTRY_SIZE;
    check_table(&bytes[..table_end], len)?;
    // The header is 8-aligned in any buffer the caller could cast sections from; for the table we
    // fall back to an error rather than copying, as for sections.
    let table: &[SectionEntry] = cast_slice(&bytes[HEADER_SIZE..table_end], "section table")?;
    let header: &Header = &cast_slice::<Header>(&bytes[..HEADER_SIZE], "header")?[0];
    Ok((header, table))
}

/// The checks of [`read_header_and_table`] on the first bytes of a file of `file_length` bytes
/// (`head` must hold the header and the whole table, or the whole file if it is shorter), returning
/// copies: for tools that stream a file rather than map it. Time independent of the file size.
pub fn parse_head(head: &[u8], file_length: u64) -> Result<(Header, Vec<SectionEntry>), FormatError> {
    let header = check_header(head, file_length, &MAGIC)?;
    let table_end = HEADER_SIZE + header.section_count as usize * TABLE_ENTRY_SIZE;
    let head_and_table = head.get(..table_end).ok_or(FormatError::TableOutOfBounds {
        count: header.section_count,
        end: table_end as u64,
        file_length: head.len() as u64,
    })?;
    let table = check_table(head_and_table, file_length)?;
    Ok((header, table))
}

/// The header checks of §7, in its order, for a container whose magic is `magic` (a field's
/// [`MAGIC`], or another file type built on the same container, such as a shard): `head` holds at
/// least the first 128 bytes of a file of `file_length` bytes. On success the section table lies
/// within the file, at `128 .. 128 + 72 × section_count`; [`check_table`] checks it.
pub fn check_header(head: &[u8], file_length: u64, magic: &[u8; 8]) -> Result<Header, FormatError> {
    let len = file_length;
    if head.len() < HEADER_SIZE {
        return Err(FormatError::TooShort { actual: len, needed: HEADER_SIZE as u64 });
    }
    let header: Header = bytemuck::pod_read_unaligned(&head[..HEADER_SIZE]);
    if header.magic != *magic {
        return Err(FormatError::BadMagic { found: header.magic, hint: magic_hint(&header.magic) });
    }
    if header.version_major != VERSION_MAJOR {
        return Err(FormatError::UnsupportedVersion {
            major: header.version_major,
            minor: header.version_minor,
            supported: VERSION_MAJOR,
        });
    }
    check_field("header_size", header.header_size as u64, HEADER_SIZE as u64)?;
    check_field("table_offset", header.table_offset, HEADER_SIZE as u64)?;
    check_field("table_entry_size", header.table_entry_size as u64, TABLE_ENTRY_SIZE as u64)?;
    if header.flags != 0 {
        return Err(FormatError::ReservedNotZero { field: "flags" });
    }
    if header.reserved0 != 0 {
        return Err(FormatError::ReservedNotZero { field: "reserved0" });
    }
    if header.reserved1 != [0; 16] {
        return Err(FormatError::ReservedNotZero { field: "reserved1" });
    }
    if header.file_length != len {
        let what = if len < header.file_length { "the file is truncated" } else { "the file has bytes appended" };
        return Err(FormatError::LengthMismatch { actual: len, expected: header.file_length, what });
    }
    if header.section_count > MAX_SECTIONS {
        return Err(FormatError::TooManySections { count: header.section_count, limit: MAX_SECTIONS });
    }
    let table_end = HEADER_SIZE as u64 + header.section_count as u64 * TABLE_ENTRY_SIZE as u64;
    if table_end > len {
        return Err(FormatError::TableOutOfBounds { count: header.section_count, end: table_end, file_length: len });
    }
    Ok(header)
}

/// The rest of §7 for a header that passed [`check_header`]: `head_and_table` is exactly the first
/// `128 + 72 × section_count` bytes of a file of `file_length` bytes. Checks the content hash,
/// then every entry (codec, alignment, order, bounds, lengths, element sizes of known kinds,
/// duplicates) and that the file ends where its last section does. Returns the entries.
pub fn check_table(head_and_table: &[u8], file_length: u64) -> Result<Vec<SectionEntry>, FormatError> {
    let len = file_length;
    let table_end = head_and_table.len() as u64;
    let stored: [u8; 32] = head_and_table[CONTENT_HASH_RANGE].try_into().expect("32 bytes");
    let computed = content_hash(head_and_table);
    if computed != stored {
        return Err(FormatError::ContentHashMismatch { stored: hex(&stored), computed: hex(&computed) });
    }
    let table: Vec<SectionEntry> = bytemuck::pod_collect_to_vec(&head_and_table[HEADER_SIZE..]);
    let mut prev_end = table_end;
    for (index, e) in table.iter().enumerate() {
        let bad = |problem: String| FormatError::BadSection { index, kind: kind_name(e.kind), problem };
        if e.codec != codec::RAW && e.codec != codec::ZSTD {
            return Err(bad(format!("unknown codec {}", e.codec)));
        }
        if e.reserved != 0 {
            return Err(bad("reserved field is not zero".into()));
        }
        if e.offset % SECTION_ALIGN != 0 {
            return Err(bad(format!("offset {} is not a multiple of {SECTION_ALIGN}", e.offset)));
        }
        if e.offset < prev_end {
            return Err(bad(format!(
                "offset {} overlaps the table or the previous section (which ends at {prev_end}); entries must be sorted by offset",
                e.offset
            )));
        }
        let end = e.offset.checked_add(e.stored_length).filter(|&end| end <= len).ok_or_else(|| {
            bad(format!(
                "stored bytes {}..{} run past the end of the file ({len} bytes)",
                e.offset,
                e.offset as u128 + e.stored_length as u128
            ))
        })?;
        if e.codec == codec::RAW && e.raw_length != e.stored_length {
            return Err(bad(format!(
                "raw section has raw_length {} but stored_length {}",
                e.raw_length, e.stored_length
            )));
        }
        if e.codec == codec::ZSTD && e.raw_length as u128 > e.stored_length as u128 * MAX_ZSTD_EXPANSION as u128 {
            return Err(bad(format!(
                "raw_length {} cannot come from {} stored bytes: a zstd frame expands at most {MAX_ZSTD_EXPANSION}-fold",
                e.raw_length, e.stored_length
            )));
        }
        if e.element_size == 0 || e.raw_length % e.element_size as u64 != 0 {
            return Err(bad(format!(
                "raw_length {} is not a multiple of element_size {}",
                e.raw_length, e.element_size
            )));
        }
        if let Some(kind) = SectionKind::from_u32(e.kind)
            && e.element_size != kind.element_size()
        {
            return Err(bad(format!("element_size is {}, the spec says {}", e.element_size, kind.element_size())));
        }
        if let Some(first) = table[..index].iter().position(|p| p.kind == e.kind) {
            return Err(FormatError::DuplicateSection { kind: kind_name(e.kind), first, second: index });
        }
        prev_end = end;
    }
    if prev_end != len {
        return Err(FormatError::LengthMismatch {
            actual: len,
            expected: prev_end,
            what: "the file does not end where its last section ends",
        });
    }
    Ok(table)
}

impl<'a> FieldReader<'a> {
    /// Validates the structure of `bytes` as a field (§7) and casts every section in place.
    ///
    /// `bytes` must be 8-byte aligned (a memory map or a `Vec<u64>`-backed buffer is); otherwise
    /// [`FormatError::Misaligned`] names the section that could not be cast.
    pub fn new(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let (header, table) = read_header_and_table(bytes)?;
        // An optional kind (§4) that is absent reads as an empty section.
        let raw = |kind: SectionKind| -> Result<&'a [u8], FormatError> {
            let Some(e) = table.iter().find(|e| e.kind == kind as u32) else {
                return if kind.is_required() {
                    Err(FormatError::MissingSection { kind: kind.name() })
                } else {
                    Ok(&[])
                };
            };
            if e.codec != codec::RAW {
                return Err(FormatError::CompressedSection { kind: kind.name(), codec: e.codec });
            }
            Ok(&bytes[e.offset as usize..(e.offset + e.stored_length) as usize])
        };
        fn typed<T: Pod>(bytes: &[u8], kind: SectionKind) -> Result<&[T], FormatError> {
            cast_slice(bytes, kind.name())
        }
        fn one<T: Pod>(bytes: &[u8], kind: SectionKind) -> Result<&T, FormatError> {
            let s: &[T] = typed(bytes, kind)?;
            expect_count(kind, s.len() as u64, 1)?;
            Ok(&s[0])
        }

        let scene: &SceneRecord = one(raw(SectionKind::Scene)?, SectionKind::Scene)?;
        let params: &ParamsRecord = one(raw(SectionKind::Params)?, SectionKind::Params)?;
        let statistics: &StatisticsRecord = one(raw(SectionKind::Statistics)?, SectionKind::Statistics)?;
        check_scene_and_params(scene, params)?;

        let l = params.direction_count as u64;
        let n = params.tile_resolution as u64;
        let lattice_side = 2 * params.lattice_n as u64 + 1;
        let reader = FieldReader {
            bytes,
            header,
            table,
            scene,
            params,
            statistics,
            directions: typed(raw(SectionKind::Directions)?, SectionKind::Directions)?,
            rotations: typed(raw(SectionKind::Rotations)?, SectionKind::Rotations)?,
            lookup: typed(raw(SectionKind::Lookup)?, SectionKind::Lookup)?,
            beams: typed(raw(SectionKind::Beams)?, SectionKind::Beams)?,
            tiles: typed(raw(SectionKind::Tiles)?, SectionKind::Tiles)?,
            leaves: typed(raw(SectionKind::Leaves)?, SectionKind::Leaves)?,
            triangles: typed(raw(SectionKind::Triangles)?, SectionKind::Triangles)?,
            provenance: typed(raw(SectionKind::Provenance)?, SectionKind::Provenance)?,
            sources: typed(raw(SectionKind::Sources)?, SectionKind::Sources)?,
            inputs: typed(raw(SectionKind::Inputs)?, SectionKind::Inputs)?,
            strings: raw(SectionKind::Strings)?,
            materials: typed(raw(SectionKind::Materials)?, SectionKind::Materials)?,
            cameras: typed(raw(SectionKind::Cameras)?, SectionKind::Cameras)?,
            lights: typed(raw(SectionKind::Lights)?, SectionKind::Lights)?,
            duplicates: typed(raw(SectionKind::Duplicates)?, SectionKind::Duplicates)?,
        };
        expect_count(SectionKind::Directions, reader.directions.len() as u64, l)?;
        expect_count(SectionKind::Rotations, reader.rotations.len() as u64, l)?;
        expect_count(SectionKind::Beams, reader.beams.len() as u64, l)?;
        expect_count(SectionKind::Lookup, reader.lookup.len() as u64, lattice_side * lattice_side)?;
        expect_count(SectionKind::Tiles, reader.tiles.len() as u64, l * n * n)?;
        expect_count(SectionKind::Triangles, reader.triangles.len() as u64, scene.triangle_count)?;
        expect_count(SectionKind::Provenance, reader.provenance.len() as u64, scene.triangle_count)?;
        expect_count(SectionKind::Sources, reader.sources.len() as u64, scene.source_count as u64)?;
        expect_count(SectionKind::Inputs, reader.inputs.len() as u64, scene.input_count as u64)?;
        Ok(reader)
    }

    /// The entry of a section kind, if present.
    pub fn entry(&self, kind: SectionKind) -> Option<&'a SectionEntry> {
        self.table.iter().find(|e| e.kind == kind as u32)
    }

    /// A name from STRINGS, or `None` if the reference is out of bounds or not UTF-8.
    pub fn string(&self, offset: u32, length: u32) -> Option<&'a str> {
        let start = offset as usize;
        let bytes = self.strings.get(start..start.checked_add(length as usize)?)?;
        std::str::from_utf8(bytes).ok()
    }
}

/// The O(1) sanity checks on SCENE and PARAMS that later size computations rely on.
fn check_scene_and_params(scene: &SceneRecord, params: &ParamsRecord) -> Result<(), FormatError> {
    let invalid = |section: &'static str, problem: String| Err(FormatError::Invalid { section, problem });
    if !(scene.radius.is_finite() && scene.radius > 0.0) {
        return invalid("SCENE", format!("radius {} is not a positive finite number", scene.radius));
    }
    if !scene.center.iter().all(|c| c.is_finite()) {
        return invalid("SCENE", format!("center {:?} is not finite", scene.center));
    }
    if scene.triangle_count > u32::MAX as u64 {
        return invalid("SCENE", format!("triangle_count {} exceeds 2^32 - 1", scene.triangle_count));
    }
    let big_n = params.lattice_n as u64;
    if big_n == 0 || big_n > 4096 {
        return invalid("PARAMS", format!("lattice_n {big_n} is outside 1..=4096"));
    }
    if params.direction_count as u64 != 2 * big_n * big_n + 1 {
        return invalid("PARAMS", format!("direction_count {} is not 2N²+1 for N = {big_n}", params.direction_count));
    }
    if params.tile_resolution == 0 || params.tile_resolution > 1 << 16 {
        return invalid("PARAMS", format!("tile_resolution {} is outside 1..=65536", params.tile_resolution));
    }
    if params.max_depth > MAX_DEPTH {
        return invalid("PARAMS", format!("max_depth {} exceeds {MAX_DEPTH}", params.max_depth));
    }
    if !(params.margin.is_finite() && params.margin > 0.0 && params.margin < scene.radius) {
        return invalid("PARAMS", format!("margin {} is not in (0, radius)", params.margin));
    }
    Ok(())
}

fn expect_count(kind: SectionKind, actual: u64, expected: u64) -> Result<(), FormatError> {
    if actual == expected {
        Ok(())
    } else {
        Err(FormatError::WrongElementCount { kind: kind.name(), actual, expected })
    }
}

fn check_field(field: &'static str, found: u64, expected: u64) -> Result<(), FormatError> {
    if found == expected { Ok(()) } else { Err(FormatError::BadHeaderField { field, found, expected }) }
}

/// Casts bytes to a slice of `T`, or says which section could not be cast.
pub(crate) fn cast_slice<'b, T: Pod>(bytes: &'b [u8], kind: &'static str) -> Result<&'b [T], FormatError> {
    // An empty section (or an absent optional one) casts whatever its address.
    if bytes.is_empty() {
        return Ok(&[]);
    }
    bytemuck::try_cast_slice(bytes).map_err(|e| match e {
        bytemuck::PodCastError::TargetAlignmentGreaterAndInputNotAligned => {
            FormatError::Misaligned { kind, address: bytes.as_ptr() as usize }
        }
        _ => FormatError::Invalid {
            section: kind,
            problem: format!("length {} does not fit the element type", bytes.len()),
        },
    })
}

/// The content hash of §3.1 over `header_and_table` (the first `128 + 72 × count` bytes).
pub fn content_hash(header_and_table: &[u8]) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(&header_and_table[..CONTENT_HASH_RANGE.start]);
    h.update(&[0u8; 32]);
    h.update(&header_and_table[CONTENT_HASH_RANGE.end..]);
    *h.finalize().as_bytes()
}

/// A guess at what damaged or foreign bytes are, for the bad-magic message.
fn magic_hint(found: &[u8; 8]) -> &'static str {
    if *found == SHARD_MAGIC {
        " (this is a shard of a sharded bake, `vlf-bake bake --shard`: merge the shards into a field with `vlf-bake merge`)"
    } else if found[1..4] == MAGIC[1..4] {
        if found[0] == MAGIC[0] & 0x7f {
            " (the first byte lost its high bit: the file went through a 7-bit text transfer)"
        } else if found[4..7] == *b"\r\r\n" {
            " (\\n became \\r\\n: the file went through a text-mode transfer that converts line endings)"
        } else if found[4..6] == *b"\n\x1a" {
            " (\\r\\n became \\n: the file went through a text-mode transfer that converts line endings)"
        } else {
            " (the magic is damaged)"
        }
    } else if found[..4] == *b"glTF"
        || found[0] == b'{'
        || found[..2] == *b"v "
        || found[0] == b'#'
        || found[..2] == *b"o "
    {
        " (this looks like a mesh: bake it with `vlf-bake bake`)"
    } else {
        ""
    }
}
