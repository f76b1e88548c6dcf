//! One error variant per fault, each carrying what a person needs to find it.

/// Everything that can be wrong with the bytes of a field file.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[non_exhaustive]
#[deny(missing_docs)]
pub enum FormatError {
    /// The file is shorter than the header.
    #[error("file is {actual} bytes, shorter than the {needed}-byte header: not a VLF field, or truncated")]
    TooShort {
        /// The file's length in bytes.
        actual: u64,
        /// The header's size (128).
        needed: u64,
    },
    /// The first 8 bytes are not the VLF magic: not a field, or damaged in transfer.
    #[error("bad magic number {found:02x?}: not a VLF field{hint}")]
    BadMagic {
        /// The bytes found.
        found: [u8; 8],
        /// A guess at what happened (a text-mode transfer, a mesh file), or empty.
        hint: &'static str,
    },
    /// The file's major version is not the one this reader reads.
    #[error(
        "format version {major}.{minor} is not supported: this reader reads format {supported}.x{}",
        version_hint(*major, *supported)
    )]
    UnsupportedVersion {
        /// The file's major version.
        major: u16,
        /// The file's minor version.
        minor: u16,
        /// The major version this reader reads.
        supported: u16,
    },
    /// A header field that has one valid value has another.
    #[error("header field `{field}` is {found}, expected {expected}")]
    BadHeaderField {
        /// The field's name.
        field: &'static str,
        /// Its value.
        found: u64,
        /// The value the spec requires.
        expected: u64,
    },
    /// A reserved header field or flag is not zero.
    #[error("header field `{field}` must be zero (reserved), found nonzero bytes")]
    ReservedNotZero {
        /// The field's name.
        field: &'static str,
    },
    /// The file's length disagrees with its header or its last section: truncated or appended to.
    #[error("file is {actual} bytes but its header says {expected}: {what}")]
    LengthMismatch {
        /// The file's length in bytes.
        actual: u64,
        /// The length the header or table implies.
        expected: u64,
        /// Which of the two, in words.
        what: &'static str,
    },
    /// The section table claims more entries than any reader accepts.
    #[error("section table has {count} entries, more than the limit of {limit}")]
    TooManySections {
        /// The claimed count.
        count: u32,
        /// The limit.
        limit: u32,
    },
    /// The section table runs past the end of the file.
    #[error("section table ({count} entries) ends at byte {end}, past the end of the file ({file_length})")]
    TableOutOfBounds {
        /// The claimed number of entries.
        count: u32,
        /// Where the table would end.
        end: u64,
        /// The file's length in bytes.
        file_length: u64,
    },
    /// The content hash over the header and table does not match: they are corrupt.
    #[error("content hash mismatch: the header or section table is corrupt (stored {stored}, computed {computed})")]
    ContentHashMismatch {
        /// The hash in the header, in hex.
        stored: String,
        /// The hash of the bytes, in hex.
        computed: String,
    },
    /// A section table entry is invalid (codec, offset, length, element size, order).
    #[error("section {index} ({kind}): {problem}")]
    BadSection {
        /// The entry's index in the table.
        index: usize,
        /// The section's kind name.
        kind: String,
        /// What is wrong, in words.
        problem: String,
    },
    /// A section the format requires is absent.
    #[error("required section {kind} is missing")]
    MissingSection {
        /// The section's kind name.
        kind: &'static str,
    },
    /// A section kind appears twice in the table.
    #[error("section {kind} appears twice (table entries {first} and {second})")]
    DuplicateSection {
        /// The section's kind name.
        kind: String,
        /// The first entry's index.
        first: usize,
        /// The second entry's index.
        second: usize,
    },
    /// A section is stored compressed, and this reader only casts raw sections in place.
    #[error(
        "section {kind} is stored with codec {codec} (zstd): this is a packed field; decode it with vlf-runtime's `packed` feature (on by default) or unpack it first with `vlf-bake unpack`"
    )]
    CompressedSection {
        /// The section's kind name.
        kind: &'static str,
        /// The section's codec number.
        codec: u32,
    },
    /// A section has a different number of elements than the header and parameters imply.
    #[error("section {kind} has {actual} elements, expected {expected}")]
    WrongElementCount {
        /// The section's kind name.
        kind: &'static str,
        /// Its element count.
        actual: u64,
        /// The count implied by SCENE and PARAMS.
        expected: u64,
    },
    /// The bytes are not aligned in memory for a section's element type (the buffer, not the file, is at fault).
    #[error(
        "section {kind} is not aligned in memory for its element type (address {address:#x}); map the file or copy it into an aligned buffer"
    )]
    Misaligned {
        /// The section's kind name.
        kind: &'static str,
        /// The section's address in memory.
        address: usize,
    },
    /// A value inside a record is out of its valid range.
    #[error("{section}: {problem}")]
    Invalid {
        /// The section (or record) name.
        section: &'static str,
        /// What is wrong, in words.
        problem: String,
    },
    /// A section's BLAKE3 hash does not match its table entry (found by full verification).
    #[error("section {kind} is corrupt: its BLAKE3 hash is {computed}, the table says {stored}")]
    SectionHashMismatch {
        /// The section's kind name.
        kind: String,
        /// The hash in the table, in hex.
        stored: String,
        /// The hash of the bytes, in hex.
        computed: String,
    },
    /// A padding byte between sections is not zero (found by full verification).
    #[error("padding byte at offset {offset} is {value:#04x}, must be zero")]
    NonZeroPadding {
        /// The byte's offset in the file.
        offset: u64,
        /// Its value.
        value: u8,
    },
    /// A packed section's bytes do not decode to what its table entry says.
    #[error("section {kind} does not decode: {problem}")]
    Decode {
        /// The section's kind name.
        kind: String,
        /// What went wrong, in words.
        problem: String,
    },
    /// A packed field would unpack to more bytes than the limit for decoding it in memory.
    #[error(
        "the field unpacks to {bytes} bytes, more than the limit of {limit} bytes for decoding it in memory; \
         `vlf-bake unpack` decodes it to a file instead"
    )]
    UnpackedTooLarge {
        /// The unpacked size.
        bytes: u64,
        /// The limit.
        limit: u64,
    },
    /// The memory to hold the unpacked field could not be allocated.
    #[error("cannot allocate {bytes} bytes to hold the field in memory")]
    OutOfMemory {
        /// The size asked for.
        bytes: u64,
    },
}

/// Lower-case hex of a hash, for messages and `dump`.
pub fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push_str(&format!("{b:02x}"));
    }
    s
}

/// What to do about a field of another major version.
fn version_hint(major: u16, supported: u16) -> &'static str {
    if major < supported {
        " (the field was baked by an older vlf-bake: rebake it from its meshes with this one)"
    } else {
        " (the field was baked by a newer vlf-bake: read it with that version or newer)"
    }
}
