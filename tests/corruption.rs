//! Damaged files give errors, never panics, and each error names what is wrong:
//!
//! - every truncation is refused at open as a truncation;
//! - a flipped bit anywhere in the header or the section table is refused at open, by the header
//!   field it damaged (magic, version, sizes, length, reserved fields) or by the content hash
//!   (the hashes and the table, which the content hash covers);
//! - a flipped bit anywhere in the payload is caught by the full verification that
//!   `vlf-bake dump --verify` runs (`vlf_bake::inspect::verify`), by the section it damaged (that
//!   section's hash) or by the padding byte's offset; SCENE and PARAMS values that the open
//!   checks are caught at open already.
//!
//! The real command line on a sample of these is tested in `crates/vlf-bake/tests/reliability.rs`.

#![forbid(unsafe_code)]

use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_format::{FormatError, HEADER_SIZE, SectionKind, TABLE_ENTRY_SIZE, kind_name};
use vlf_runtime::{Field, OpenError};

/// A complete, tiny field (a 12-triangle box, 3 directions, 2×2 tiles): a few KiB.
fn tiny_field() -> Vec<u8> {
    let scene = Scene::from_triangles("box", &generate::closed_box([0.0; 3], [1.0, 2.0, 3.0])).unwrap();
    let (dir, _field) = vlf_tests::bake(&scene, 3, 2, DepthPolicy { leaf_size: 2, max_depth: 3 });
    std::fs::read(dir.path().join("scene.vlf")).unwrap()
}

/// Opens and fully verifies bytes (aligned copy, as `Field::from_bytes` does): what
/// `vlf-bake dump --verify` does with a file.
fn open_and_verify(bytes: &[u8]) -> Result<(), String> {
    let field = Field::from_bytes(bytes).map_err(|e| e.to_string())?;
    vlf_bake::inspect::verify(field.reader(), &mut |_, _| {}).map(|_| ()).map_err(|e| e.to_string())
}

/// The format error behind an open error.
fn format_error(e: OpenError) -> FormatError {
    match e {
        OpenError::Bytes(e) | OpenError::Format { error: e, .. } => e,
        OpenError::Io { .. } => panic!("bytes cannot give an I/O error: {e}"),
    }
}

/// The end of the section table: where the payload starts.
fn table_end(bytes: &[u8]) -> usize {
    HEADER_SIZE + TABLE_ENTRY_SIZE * u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize
}

#[test]
fn the_tiny_field_verifies() {
    let bytes = tiny_field();
    open_and_verify(&bytes).unwrap();
    assert!(bytes.len() < 8192, "the sweeps below flip every bit; keep the fixture tiny ({} bytes)", bytes.len());
}

#[test]
fn every_truncation_is_refused_at_open_as_a_truncation() {
    let bytes = tiny_field();
    for len in 0..bytes.len() {
        let err =
            Field::from_bytes(&bytes[..len]).err().unwrap_or_else(|| panic!("truncated to {len} bytes but opened"));
        let message = err.to_string();
        match format_error(err) {
            FormatError::TooShort { .. } | FormatError::LengthMismatch { .. } => {}
            other => panic!("truncated to {len}: unexpected error {other}"),
        }
        assert!(message.contains("truncated"), "truncated to {len}: the message does not say so: {message}");
    }
}

/// Whether `e` is the error a flipped bit at header offset `at` must give, and its message names
/// what is wrong.
fn names_the_damage(at: usize, e: &FormatError) -> bool {
    let m = e.to_string();
    let field =
        |name: &str| matches!(e, FormatError::BadHeaderField { field, .. } if *field == name) && m.contains(name);
    let reserved =
        |name: &str| matches!(e, FormatError::ReservedNotZero { field } if *field == name) && m.contains(name);
    let hash = matches!(e, FormatError::ContentHashMismatch { .. }) && m.contains("header or section table is corrupt");
    match at {
        0..8 => matches!(e, FormatError::BadMagic { .. }) && m.contains("bad magic"),
        8..10 => matches!(e, FormatError::UnsupportedVersion { .. }) && m.contains("format version"),
        // Any minor version is read; the content hash covers it.
        10..12 => hash,
        12..16 => field("header_size"),
        16..24 => {
            matches!(e, FormatError::LengthMismatch { .. }) && (m.contains("truncated") || m.contains("appended"))
        }
        24..32 => field("table_offset"),
        // A larger count runs past the limit or the file, a smaller one hashes a shorter table.
        32..36 => {
            (matches!(e, FormatError::TooManySections { .. } | FormatError::TableOutOfBounds { .. })
                && m.contains("section table"))
                || hash
        }
        36..40 => field("table_entry_size"),
        40..44 => reserved("flags"),
        44..48 => reserved("reserved0"),
        // The content hash itself, the input hash.
        48..112 => hash,
        112..128 => reserved("reserved1"),
        // The section table.
        _ => hash,
    }
}

#[test]
fn a_flipped_bit_in_the_header_or_table_is_refused_at_open_naming_what_is_wrong() {
    let bytes = tiny_field();
    for at in 0..table_end(&bytes) {
        for bit in 0..8 {
            let mut damaged = bytes.clone();
            damaged[at] ^= 1 << bit;
            let err = Field::from_bytes(&damaged)
                .err()
                .unwrap_or_else(|| panic!("bit {bit} of byte {at} flipped but opened"));
            let e = format_error(err);
            assert!(names_the_damage(at, &e), "bit {bit} of byte {at}: wrong or vague error: {e}");
        }
    }
}

#[test]
fn a_flipped_bit_anywhere_in_the_payload_fails_verification_naming_the_section() {
    let bytes = tiny_field();
    let table = {
        let field = Field::from_bytes(&bytes).unwrap();
        field.reader().table.to_vec()
    };
    let mut sections_hit = std::collections::BTreeSet::new();
    let mut padding_hit = 0;
    for at in table_end(&bytes)..bytes.len() {
        let section = table.iter().find(|e| (e.offset..e.offset + e.stored_length).contains(&(at as u64)));
        for bit in 0..8 {
            let mut damaged = bytes.clone();
            damaged[at] ^= 1 << bit;
            let what = format!("bit {bit} of byte {at} ({})", section.map_or("padding".into(), |e| kind_name(e.kind)));
            let field = match Field::from_bytes(&damaged) {
                Ok(field) => field,
                // SCENE and PARAMS values that later size computations rely on are checked at
                // open, by name or by the section whose size they no longer match.
                Err(err) => {
                    let kind = section.map(|e| e.kind);
                    assert!(
                        kind == Some(SectionKind::Scene as u32) || kind == Some(SectionKind::Params as u32),
                        "{what}: refused at open, but the open checks do not read that byte: {err}"
                    );
                    let e = format_error(err);
                    assert!(
                        matches!(&e, FormatError::Invalid { section: "SCENE" | "PARAMS", .. })
                            || matches!(e, FormatError::WrongElementCount { .. }),
                        "{what}: {e}"
                    );
                    continue;
                }
            };
            let e = vlf_bake::inspect::verify(field.reader(), &mut |_, _| {})
                .err()
                .unwrap_or_else(|| panic!("{what}: not caught by the full verification"));
            match (section, &e) {
                (Some(entry), FormatError::SectionHashMismatch { kind, .. }) if *kind == kind_name(entry.kind) => {
                    assert!(e.to_string().contains(&format!("section {kind} is corrupt")), "{e}");
                    sections_hit.insert(kind.clone());
                }
                (None, FormatError::NonZeroPadding { offset, .. }) if *offset == at as u64 => {
                    assert!(e.to_string().contains(&format!("padding byte at offset {at}")), "{e}");
                    padding_hit += 1;
                }
                _ => panic!("{what}: the error does not name the damaged section or byte: {e}"),
            }
        }
    }
    // Every section was swept, and the padding too.
    assert_eq!(sections_hit.len(), table.len(), "{sections_hit:?}");
    assert!(padding_hit > 0);
}

#[test]
fn foreign_and_damaged_magic_files_are_named() {
    let bytes = tiny_field();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".repeat(20), "looks like a mesh"),
        (b"glTF\x02\x00\x00\x00".iter().copied().chain(std::iter::repeat_n(0, 200)).collect(), "looks like a mesh"),
        // A CR-LF translation turns "\r\n" into "\r\r\n".
        ([&bytes[..4], b"\r\r\n", &bytes[6..]].concat(), "line endings"),
        // A 7-bit transfer clears the high bit of the first byte.
        ([&[0x09u8][..], &bytes[1..]].concat(), "7-bit"),
        (vec![0u8; 300], "not a VLF field"),
    ];
    for (damaged, hint) in cases {
        let err = Field::from_bytes(&damaged).err().expect("foreign bytes opened");
        assert!(err.to_string().contains(hint), "{err} should mention {hint:?}");
    }
}

#[test]
fn a_future_major_version_is_refused_by_name() {
    let mut bytes = tiny_field();
    bytes[8..10].copy_from_slice(&3u16.to_le_bytes());
    let err = Field::from_bytes(&bytes).err().expect("opened a future major version");
    assert!(matches!(err, OpenError::Bytes(FormatError::UnsupportedVersion { major: 3, .. })), "{err}");
    let says = format!("format version 3.{} is not supported", vlf_format::VERSION_MINOR);
    assert!(err.to_string().contains(&says), "{err}");
    assert!(err.to_string().contains("newer vlf-bake"), "{err}");
    // And a field of the previous major version says to rebake it.
    bytes[8..10].copy_from_slice(&1u16.to_le_bytes());
    let err = Field::from_bytes(&bytes).err().expect("opened an old major version");
    assert!(err.to_string().contains("format version 1.0 is not supported"), "{err}");
    assert!(err.to_string().contains("rebake it"), "{err}");
}

#[test]
fn borrowed_bytes_are_queried_in_place_when_aligned_and_refused_when_not() {
    let bytes = tiny_field();
    let len = bytes.len();
    let mut words = vec![0u64; len.div_ceil(8) + 1];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[1..=len].copy_from_slice(&bytes);
    let shifted: &[u8] = &bytemuck::cast_slice::<u64, u8>(&words)[1..=len];
    let err = vlf_runtime::FieldView::from_bytes(shifted).unwrap_err();
    assert!(matches!(err, FormatError::Misaligned { .. }), "{err}");

    let mut words = vec![0u64; len.div_ceil(8)];
    bytemuck::cast_slice_mut::<u64, u8>(&mut words)[..len].copy_from_slice(&bytes);
    let view = vlf_runtime::FieldView::from_bytes(&bytemuck::cast_slice::<u64, u8>(&words)[..len]).unwrap();
    // The box spans [0,1]×[0,2]×[0,3]; a ray from outside along -z hits its top at z = 3.
    let hit = view.closest_hit(&vlf_runtime::Ray::new([0.5, 0.5, 10.0], [0.0, 0.0, -1.0])).unwrap();
    assert_eq!(hit.t, 7.0);
}

/// Only a regular file is mapped: a directory is named as one, and a pipe is refused at once
/// (opening it would wait for a writer, forever if none comes).
#[test]
fn a_directory_or_a_pipe_is_refused_at_open_by_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let err = Field::open(dir.path()).err().expect("a directory opened");
    assert!(err.to_string().contains("is a directory"), "{err}");
    #[cfg(unix)]
    {
        let fifo = dir.path().join("pipe.vlf");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let (tx, rx) = std::sync::mpsc::channel();
            let path = fifo.clone();
            std::thread::spawn(move || tx.send(Field::open(&path).err().map(|e| e.to_string())));
            let err = rx.recv_timeout(std::time::Duration::from_secs(20)).expect("opening a pipe hangs");
            let err = err.expect("a pipe opened");
            assert!(err.contains("not a regular file") && err.contains("pipe.vlf"), "{err}");
            assert!(err.contains("cannot be mapped: read its bytes into memory"), "{err}");
            // Reading into memory takes regular files only too: a pipe would be waited on.
            let (tx, rx) = std::sync::mpsc::channel();
            let path = fifo.clone();
            std::thread::spawn(move || tx.send(Field::read(&path).err().map(|e| e.to_string())));
            let err = rx.recv_timeout(std::time::Duration::from_secs(20)).expect("reading a pipe hangs");
            let err = err.expect("a pipe was read");
            assert!(err.contains("it is a pipe (FIFO), not a regular file"), "{err}");
        }
        // `/dev/zero` was read until memory ran out.
        let err = Field::read("/dev/zero").err().expect("/dev/zero read as a field").to_string();
        assert_eq!(err, "cannot read field /dev/zero: it is a character device, not a regular file");
    }
}
