//! A packed field (`formats/vlf.md` §8) through a runtime built with and without its `packed`
//! feature: decoded (here, refused for a bad frame, naming the section) or refused with an error
//! that names the feature. CI runs this file both ways
//! (`cargo test -p vlf-runtime --no-default-features --test packed_feature`).

use vlf_format::{Header, MAGIC, SectionEntry, SectionKind, VERSION_MAJOR, codec};
use vlf_runtime::Field;

/// A container whose one section, SCENE, claims to be a zstd frame but holds 8 bytes of garbage.
fn packed_garbage() -> Vec<u8> {
    let template = Header {
        magic: MAGIC,
        version_major: VERSION_MAJOR,
        version_minor: 0,
        header_size: 128,
        file_length: 0,
        table_offset: 128,
        section_count: 1,
        table_entry_size: 72,
        flags: 0,
        reserved0: 0,
        content_hash: [0; 32],
        input_hash: [0; 32],
        reserved1: [0; 16],
    };
    let mut table = [SectionEntry {
        kind: SectionKind::Scene as u32,
        codec: codec::ZSTD,
        offset: 0,
        stored_length: 8,
        raw_length: 128,
        element_size: 128,
        reserved: 0,
        raw_hash: [0; 32],
    }];
    let header = vlf_format::pack::lay_out(&template, &mut table).unwrap();
    let mut bytes = vlf_format::pack::head_bytes(&header, &table);
    bytes.resize(table[0].offset as usize, 0);
    bytes.extend_from_slice(b"garbage!");
    assert_eq!(bytes.len() as u64, header.file_length);
    bytes
}

#[test]
fn a_packed_field_is_decoded_or_refused_naming_the_feature() {
    let err = Field::from_bytes(&packed_garbage()).err().expect("garbage opened").to_string();
    if cfg!(feature = "packed") {
        assert!(err.contains("section SCENE does not decode"), "{err}");
    } else {
        assert!(err.contains("`packed` feature") && err.contains("vlf-bake unpack"), "{err}");
    }
}
