//! The VLF visibility-field file format, version 1 (`formats/vlf.md` is the contract).
//!
//! This crate knows bytes and invariants, not ray tracing:
//! - [`layout`]: the on-disk structs, `#[repr(C)]` and `Pod`, sizes asserted at compile time,
//!   every field documented with its unit and encoding;
//! - [`section`]: section kinds, their names and element sizes, and the codecs;
//! - [`size`]: the size model of a field, derived from the records' sizes;
//! - [`reader`]: a zero-copy reader that validates the header and section table in time
//!   independent of the file size and hands out typed slices;
//! - [`writer`]: a writer that places sections in a file in place, each byte written once, with
//!   big sections streamed or filled while others are written;
//! - [`mod@verify`]: the full verification behind `vlf-bake dump --verify`;
//! - [`shard`]: the shard files of sharded bakes (`formats/vlf-shard.md`);
//! - [`pack`]: packed fields (zstd sections, §8): layouts, and with the `zstd` feature encoding and
//!   decoding with every length and hash checked.
//!
//! Errors are values ([`FormatError`]), never panics, whatever the input bytes.

#![forbid(unsafe_code)]

#[cfg(target_endian = "big")]
compile_error!("vlf-format supports little-endian targets only: the file format is little-endian and is cast in place");

pub mod aligned;
pub mod block;
pub mod error;
pub mod layout;
pub mod pack;
pub mod reader;
pub mod section;
pub mod shard;
pub mod size;
pub mod verify;
pub mod writer;

pub use aligned::AlignedBytes;
pub use error::{FormatError, hex};
pub use layout::*;
pub use reader::{FieldReader, check_header, check_table, content_hash, parse_head, read_header_and_table};
pub use section::*;
pub use verify::{VerifyReport, verify, verify_hashes};
pub use writer::{AlignedWriter, FieldFile, HashingWriter, SectionWriter, WRITE_CHUNK};
