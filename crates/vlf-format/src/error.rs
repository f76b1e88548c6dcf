//! One error variant per fault, each carrying what a person needs to find it.

/// Everything that can be wrong with the bytes of a field file.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum FormatError {
    #[error("file is {actual} bytes, shorter than the {needed}-byte header: not a VLF field, or truncated")]
    TooShort { actual: u64, needed: u64 },
    #[error("bad magic number {found:02x?}: not a VLF field{hint}")]
    BadMagic { found: [u8; 8], hint: &'static str },
    #[error("format version {major}.{minor} is not supported: this reader reads major version {supported}")]
    UnsupportedVersion { major: u16, minor: u16, supported: u16 },
    #[error("header field `{field}` is {found}, expected {expected}")]
    BadHeaderField { field: &'static str, found: u64, expected: u64 },
    #[error("header field `{field}` must be zero (reserved), found nonzero bytes")]
    ReservedNotZero { field: &'static str },
    #[error("file is {actual} bytes but its header says {expected}: {what}")]
    LengthMismatch { actual: u64, expected: u64, what: &'static str },
    #[error("section table has {count} entries, more than the limit of {limit}")]
    TooManySections { count: u32, limit: u32 },
    #[error("section table ({count} entries) ends at byte {end}, past the end of the file ({file_length})")]
    TableOutOfBounds { count: u32, end: u64, file_length: u64 },
    #[error("content hash mismatch: the header or section table is corrupt (stored {stored}, computed {computed})")]
    ContentHashMismatch { stored: String, computed: String },
    #[error("section {index} ({kind}): {problem}")]
    BadSection { index: usize, kind: String, problem: String },
    #[error("required section {kind} is missing")]
    MissingSection { kind: &'static str },
    #[error("section {kind} appears twice (table entries {first} and {second})")]
    DuplicateSection { kind: String, first: usize, second: usize },
    #[error(
        "section {kind} is stored with codec {codec} (zstd): this is a packed field; decode it with vlf-runtime's `packed` feature (on by default) or unpack it first with `vlf-bake unpack`"
    )]
    CompressedSection { kind: &'static str, codec: u32 },
    #[error("section {kind} has {actual} elements, expected {expected}")]
    WrongElementCount { kind: &'static str, actual: u64, expected: u64 },
    #[error(
        "section {kind} is not aligned in memory for its element type (address {address:#x}); map the file or copy it into an aligned buffer"
    )]
    Misaligned { kind: &'static str, address: usize },
    #[error("{section}: {problem}")]
    Invalid { section: &'static str, problem: String },
    #[error("section {kind} is corrupt: its BLAKE3 hash is {computed}, the table says {stored}")]
    SectionHashMismatch { kind: String, stored: String, computed: String },
    #[error("padding byte at offset {offset} is {value:#04x}, must be zero")]
    NonZeroPadding { offset: u64, value: u8 },
    #[error("section {kind} does not decode: {problem}")]
    Decode { kind: String, problem: String },
    #[error("the field unpacks to {bytes} bytes, more than the limit of {limit} bytes set for decoding it in memory")]
    UnpackedTooLarge { bytes: u64, limit: u64 },
    #[error("cannot allocate {bytes} bytes to hold the field in memory")]
    OutOfMemory { bytes: u64 },
}

/// Lower-case hex of a hash, for messages and `dump`.
pub fn hex(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push_str(&format!("{b:02x}"));
    }
    s
}
