//! Damaged files give errors, never panics: every truncation, a flipped byte anywhere, foreign
//! files. A flipped byte in the header or table is caught at open (content hash); anywhere else
//! by the full verification (`dump --verify`).

use vlf_bake::{DepthPolicy, Scene, generate};
use vlf_format::FormatError;
use vlf_runtime::{Field, OpenError};

/// A complete, tiny field (a 12-triangle box, 3 directions, 2×2 tiles): a few KiB.
fn tiny_field() -> Vec<u8> {
    let scene = Scene::from_triangles("box", &generate::closed_box([0.0; 3], [1.0, 2.0, 3.0])).unwrap();
    let (dir, _field) = vlf_tests::bake(&scene, 3, 2, DepthPolicy { leaf_size: 2, max_depth: 3 });
    std::fs::read(dir.path().join("scene.vlf")).unwrap()
}

/// Opens and fully verifies bytes (aligned copy, as `Field::from_bytes` does).
fn open_and_verify(bytes: &[u8]) -> Result<(), String> {
    let field = Field::from_bytes(bytes).map_err(|e| e.to_string())?;
    vlf_bake::inspect::verify(field.reader(), &mut |_, _| {}).map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn the_tiny_field_verifies() {
    let bytes = tiny_field();
    open_and_verify(&bytes).unwrap();
    assert!(bytes.len() < 8192, "the sweep below is quadratic; keep the fixture tiny ({} bytes)", bytes.len());
}

#[test]
fn every_truncation_is_refused_at_open() {
    let bytes = tiny_field();
    for len in 0..bytes.len() {
        match Field::from_bytes(&bytes[..len]) {
            Err(OpenError::Bytes(FormatError::TooShort { .. } | FormatError::LengthMismatch { .. })) => {}
            Err(other) => panic!("truncated to {len}: unexpected error {other}"),
            Ok(_) => panic!("truncated to {len} bytes but opened"),
        }
    }
}

#[test]
fn a_flipped_byte_anywhere_is_caught() {
    let bytes = tiny_field();
    let table_end = 128 + 72 * u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize;
    for offset in 0..bytes.len() {
        for mask in [0x01u8, 0x80, 0xff] {
            let mut damaged = bytes.clone();
            damaged[offset] ^= mask;
            let opened = Field::from_bytes(&damaged);
            if offset < table_end {
                assert!(opened.is_err(), "flip at {offset} (header/table) was not caught at open");
            }
            let result = open_and_verify(&damaged);
            assert!(result.is_err(), "flip {mask:#04x} at offset {offset} was not caught");
        }
    }
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
    bytes[8..10].copy_from_slice(&2u16.to_le_bytes());
    let err = Field::from_bytes(&bytes).err().expect("opened a future major version");
    assert!(matches!(err, OpenError::Bytes(FormatError::UnsupportedVersion { major: 2, .. })), "{err}");
    assert!(err.to_string().contains("format version 2.0 is not supported"), "{err}");
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
