//! Packed fields (`formats/vlf.md` §8): `unpack(pack(f))` is `f` byte for byte for every fixture and
//! several parameter sets; a packed field opens in the runtime and answers exactly as the raw one;
//! packing does not depend on the thread count; damaged packed files give errors, never panics,
//! through open, the full verification and `unpack`.

#![forbid(unsafe_code)]

use std::io::Cursor;
use std::path::{Path, PathBuf};
use vlf_bake::{BakeConfig, DepthPolicy, NoProgress, Scene, generate, import, pack};
use vlf_format::{FormatError, Header, SectionEntry, SectionKind, codec};
use vlf_runtime::{Field, Hit, OpenError, OpenOptions, Ray};
use vlf_tests::fixtures;

fn bake(scene: &Scene, dir: &Path, name: &str, directions: u32, tiles: u32, depth: DepthPolicy) -> PathBuf {
    let path = dir.join(name);
    let config = BakeConfig { directions: Some(directions), tiles: Some(tiles), depth, ..BakeConfig::default() };
    vlf_bake::bake_scene(scene, &config, &path, &NoProgress).expect("bake");
    path
}

fn mesh(name: &str) -> Scene {
    import::import_paths(&[fixtures().join("meshes").join(name)]).expect("import")
}

const DEFAULT_DEPTH: DepthPolicy = DepthPolicy { leaf_size: 4, max_depth: 8 };

/// Packs `raw` at `level` into `raw` + ".packed" and returns the packed path.
fn pack_at(raw: &Path, level: i32) -> PathBuf {
    let packed = raw.with_extension(format!("packed{level}"));
    let summary = pack::pack_path(raw, &packed, level, &NoProgress).expect("pack");
    assert_eq!(summary.packed_bytes, std::fs::metadata(&packed).unwrap().len());
    packed
}

/// The header and table at the start of `bytes` (which must pass the open checks).
fn head(bytes: &[u8]) -> (Header, Vec<SectionEntry>) {
    vlf_format::parse_head(bytes, bytes.len() as u64).expect("a sound head")
}

/// Recomputes the content hash of `bytes` over its header and table (§3.1).
fn rehash(bytes: &mut [u8]) {
    let count = u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize;
    let hash = vlf_format::content_hash(&bytes[..128 + 72 * count]);
    bytes[vlf_format::CONTENT_HASH_RANGE].copy_from_slice(&hash);
}

/// `bytes` with its table changed by `edit` and the content hash recomputed, so the change gets
/// past the open checks to the decoder.
fn with_table(bytes: &[u8], edit: impl FnOnce(&mut [SectionEntry])) -> Vec<u8> {
    let (_, mut table) = head(bytes);
    edit(&mut table);
    let mut out = bytes.to_vec();
    out[128..128 + 72 * table.len()].copy_from_slice(bytemuck::cast_slice(&table));
    rehash(&mut out);
    out
}

/// What `dump --verify` checks of a packed field, on bytes: open (every frame, length and hash),
/// the packed file's padding, then the full verification of the decoded field.
fn full_check(bytes: &[u8]) -> Result<(), String> {
    let field = Field::from_bytes(bytes).map_err(|e| e.to_string())?;
    let (_, table) = head(bytes);
    vlf_format::pack::check_padding(&mut Cursor::new(bytes), &table).map_err(|e| e.to_string())?;
    vlf_bake::inspect::verify(field.reader(), &mut |_, _| {}).map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn unpack_restores_every_fixture_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let linear = DepthPolicy { leaf_size: 4, max_depth: 0 };
    let deep = DepthPolicy { leaf_size: 1, max_depth: 12 };
    let cases = [
        ("bunny.obj", 33, 16, DEFAULT_DEPTH, 3),
        ("bunny.obj", 129, 32, DEFAULT_DEPTH, 1),
        ("bunny.obj", 9, 8, linear, 9),
        ("bunny.obj", 19, 24, deep, 3),
        ("bunny_scene.glb", 33, 16, DEFAULT_DEPTH, 3),
        ("bunny_scene.glb", 3, 2, deep, 19),
        ("Box.gltf", 33, 16, DEFAULT_DEPTH, 3),
        ("Box.gltf", 3, 2, linear, 1),
    ];
    for (i, (name, directions, tiles, depth, level)) in cases.into_iter().enumerate() {
        let label = format!("{name} {directions}×{tiles}² {depth:?} level {level}");
        let raw = bake(&mesh(name), dir.path(), &format!("f{i}.vlf"), directions, tiles, depth);
        let packed = pack_at(&raw, level);
        let unpacked = dir.path().join(format!("f{i}.unpacked.vlf"));
        let summary = pack::unpack_path(&packed, &unpacked, &NoProgress).expect("unpack");
        let (raw_bytes, packed_bytes) = (std::fs::read(&raw).unwrap(), std::fs::read(&packed).unwrap());
        assert!(std::fs::read(&unpacked).unwrap() == raw_bytes, "{label}: unpack did not restore the field");
        assert!(packed_bytes.len() < raw_bytes.len(), "{label}: packing did not pay");
        let (raw_head, packed_head) = (head(&raw_bytes), head(&packed_bytes));
        assert_eq!(summary.content_hash, vlf_format::hex(&raw_head.0.content_hash), "{label}");
        // §8.3: the raw field's header and table follow from the packed ones alone.
        assert_eq!(vlf_format::pack::unpacked_layout(&packed_head.0, &packed_head.1).unwrap(), raw_head, "{label}");
        assert!(vlf_format::pack::is_canonical(&packed_head.1), "{label}: packed layout is not canonical");
        // §8.2: compressed exactly where the frame is shorter; the big sections always are.
        for e in &packed_head.1 {
            assert_eq!(e.codec == codec::ZSTD, e.stored_length < e.raw_length, "{label}: {e:?}");
        }
        let leaves_entry = packed_head.1.iter().find(|e| e.kind == SectionKind::Leaves as u32).unwrap();
        assert_eq!(leaves_entry.codec, codec::ZSTD, "{label}");
    }
}

/// Every field of a hit, with `t`, `u` and `v` as bits.
fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits()))
}

#[test]
fn a_packed_field_opens_and_answers_exactly_like_the_raw_field() {
    let dir = tempfile::tempdir().unwrap();
    // Over 8 MiB, so that opening decodes on several threads.
    let raw_path = bake(&mesh("bunny.obj"), dir.path(), "bunny.vlf", 129, 64, DEFAULT_DEPTH);
    let packed_path = pack_at(&raw_path, 3);
    let raw = Field::open(&raw_path).unwrap();
    assert!(raw.len_bytes() > 8 << 20);
    assert!(!raw.is_packed() && raw.packed_layout().is_none());
    let packed_bytes = std::fs::read(&packed_path).unwrap();
    let opened = [
        Field::open(&packed_path).unwrap(),
        Field::read(&packed_path).unwrap(),
        Field::from_bytes(&packed_bytes).unwrap(),
    ];
    let families = vlf_tests::ray_families(&raw, 2000, 11);
    for packed in &opened {
        assert!(packed.is_packed());
        assert_eq!(packed.packed_layout().unwrap().header.file_length, packed_bytes.len() as u64);
        assert_eq!(packed.content_hash(), raw.content_hash(), "the decoded field is the raw field");
        assert!(packed.reader().bytes == raw.reader().bytes);
        assert_eq!(packed.reader().bytes.as_ptr() as usize % 64, 0, "the decoded buffer is 64-byte aligned");
        for (family, rays) in &families {
            for ray in rays {
                assert_eq!(bits(packed.closest_hit(ray)), bits(raw.closest_hit(ray)), "{family}: {ray:?}");
                assert_eq!(packed.any_hit(ray), raw.any_hit(ray), "{family}: {ray:?}");
            }
        }
        assert_eq!(packed.provenance(7), raw.provenance(7));
    }
    // The full verification passes on the decoded field and the packed file.
    full_check(&packed_bytes).unwrap();
    // With several damaged sections, the first in table order is named, whichever thread saw it.
    let (_, table) = head(&packed_bytes);
    let mut damaged = packed_bytes.clone();
    for e in table.iter().filter(|e| e.codec == codec::ZSTD && e.stored_length > 1000) {
        damaged[(e.offset + e.stored_length / 2) as usize] ^= 0x10;
    }
    let first = table.iter().find(|e| e.codec == codec::ZSTD && e.stored_length > 1000).unwrap();
    for _ in 0..5 {
        let err = Field::from_bytes(&damaged).err().expect("damaged sections opened").to_string();
        assert!(err.contains(&format!("section {} ", vlf_format::kind_name(first.kind))), "{err}");
    }
    let bounded = OpenOptions::new().max_unpacked_bytes(packed_bytes.len() as u64).open(&packed_path);
    assert!(
        matches!(&bounded, Err(OpenError::Format { error: FormatError::UnpackedTooLarge { .. }, .. })),
        "{:?}",
        bounded.err()
    );
    // A limit does not apply to raw fields, which are mapped, not decoded.
    OpenOptions::new().max_unpacked_bytes(1).open(&raw_path).unwrap();
}

#[test]
fn packing_gives_identical_bytes_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::from_triangles("random", &generate::random_cube(3000, 0.05, 7)).unwrap();
    let raw = bake(&scene, dir.path(), "random.vlf", 129, 32, DEFAULT_DEPTH);
    let packed: Vec<Vec<u8>> = [1, 2, 3]
        .into_iter()
        .map(|threads| {
            let out = dir.path().join(format!("t{threads}.packed"));
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| pack::pack_path(&raw, &out, 3, &NoProgress)).unwrap();
            std::fs::read(&out).unwrap()
        })
        .collect();
    assert!(packed[0] == packed[1] && packed[1] == packed[2], "thread count changed the packed bytes");
}

/// A complete, tiny field (the 12-triangle box of `corruption.rs`), packed: a few KiB.
fn tiny_packed() -> (tempfile::TempDir, PathBuf, Vec<u8>) {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::from_triangles("box", &generate::closed_box([0.0; 3], [1.0, 2.0, 3.0])).unwrap();
    let raw = bake(&scene, dir.path(), "box.vlf", 3, 2, DepthPolicy { leaf_size: 2, max_depth: 3 });
    let packed = pack_at(&raw, 3);
    let bytes = std::fs::read(&packed).unwrap();
    (dir, packed, bytes)
}

/// A flipped byte in the header, table or padding is caught; in a compressed section it is caught
/// unless the frame still decodes to the same raw bytes (zstd ignores a few bits of its
/// bitstreams): stored bytes are checked through what they decode to (`formats/vlf.md` §8.5), so
/// no flip changes the field undetected.
#[test]
fn no_flipped_byte_of_a_packed_field_changes_it_undetected() {
    let (_dir, _, bytes) = tiny_packed();
    let original = Field::from_bytes(&bytes).unwrap();
    assert!(bytes.len() < 8192, "the sweep is quadratic; keep the fixture tiny ({} bytes)", bytes.len());
    assert!(head(&bytes).1.iter().any(|e| e.codec == codec::ZSTD), "the tiny field has a compressed section");
    full_check(&bytes).unwrap();
    let table_end = 128 + 72 * head(&bytes).1.len();
    for offset in 0..bytes.len() {
        for mask in [0x01u8, 0x80, 0xff] {
            let mut damaged = bytes.clone();
            damaged[offset] ^= mask;
            if offset < table_end {
                assert!(Field::from_bytes(&damaged).is_err(), "flip at {offset} (header/table) was not caught at open");
            }
            if full_check(&damaged).is_ok() {
                let field = Field::from_bytes(&damaged).unwrap();
                let in_frame = head(&bytes).1.iter().any(|e| {
                    e.codec == codec::ZSTD && (e.offset..e.offset + e.stored_length).contains(&(offset as u64))
                });
                assert!(
                    in_frame && field.reader().bytes == original.reader().bytes,
                    "flip {mask:#04x} at offset {offset} changed the field undetected"
                );
            }
        }
    }
}

#[test]
fn every_truncation_of_a_packed_field_is_refused_at_open() {
    let (_dir, _, bytes) = tiny_packed();
    for len in 0..bytes.len() {
        match Field::from_bytes(&bytes[..len]) {
            Err(OpenError::Bytes(FormatError::TooShort { .. } | FormatError::LengthMismatch { .. })) => {}
            Err(other) => panic!("truncated to {len}: unexpected error {other}"),
            Ok(_) => panic!("truncated to {len} bytes but opened"),
        }
    }
}

/// The first compressed section of the tiny packed field, and its table index.
fn first_zstd(bytes: &[u8]) -> (usize, SectionEntry) {
    let (_, table) = head(bytes);
    table.iter().copied().enumerate().find(|(_, e)| e.codec == codec::ZSTD).expect("a compressed section")
}

#[test]
fn lying_raw_lengths_and_hashes_are_named_by_open_verify_and_unpack() {
    let (dir, _, bytes) = tiny_packed();
    let (i, e) = first_zstd(&bytes);
    let name = vlf_format::kind_name(e.kind);
    let el = e.element_size as u64;
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("raw_length one element short", with_table(&bytes, |t| t[i].raw_length -= el), "does not decode"),
        ("raw_length one element long", with_table(&bytes, |t| t[i].raw_length += el), "does not decode"),
        ("raw_hash", with_table(&bytes, |t| t[i].raw_hash[0] ^= 1), "BLAKE3"),
        (
            "compressed payload",
            {
                let mut b = bytes.clone();
                b[(e.offset + e.stored_length / 2) as usize] ^= 0x40;
                b
            },
            "",
        ),
    ];
    for (what, damaged, says) in cases {
        let open = Field::from_bytes(&damaged).err().unwrap_or_else(|| panic!("{what}: opened")).to_string();
        assert!(open.contains(&name) && open.contains(says), "{what}: open says {open}");
        assert!(full_check(&damaged).is_err(), "{what}: passed the full check");
        let path = dir.path().join("damaged.packed");
        std::fs::write(&path, &damaged).unwrap();
        let out = dir.path().join("out.vlf");
        let err = pack::unpack_path(&path, &out, &NoProgress).expect_err(what).to_string();
        assert!(err.contains(&name), "{what}: unpack says {err}");
        assert!(!out.exists(), "{what}: a failed unpack left an output");
    }
}

#[test]
fn a_decompression_bomb_is_refused_before_or_without_allocating_its_claim() {
    let (dir, _, bytes) = tiny_packed();
    let (i, e) = first_zstd(&bytes);
    let el = e.element_size as u64;
    let bound = e.stored_length * vlf_format::MAX_ZSTD_EXPANSION / el * el;
    // More than any frame of that size can produce: refused with the table checks, at open.
    let over = with_table(&bytes, |t| t[i].raw_length = bound + el);
    let err = Field::from_bytes(&over).err().expect("a claim past the bound opened").to_string();
    assert!(err.contains("expands at most"), "{err}");
    // A claim within the bound (the buffer is allocated lazily zeroed) that the frame does not back.
    let within = with_table(&bytes, |t| t[i].raw_length = bound);
    let err = Field::from_bytes(&within).err().expect("an unbacked claim opened").to_string();
    assert!(err.contains("does not decode"), "{err}");
    // A far larger claim spread over every section, within the bound: refused by a caller's limit
    // before anything is allocated.
    let huge = with_table(&bytes, |t| {
        for e in t.iter_mut().filter(|e| e.codec == codec::ZSTD) {
            e.raw_length =
                e.stored_length * vlf_format::MAX_ZSTD_EXPANSION / e.element_size as u64 * e.element_size as u64;
        }
    });
    let (huge_header, _) = vlf_format::pack::unpacked_layout(&head(&huge).0, &head(&huge).1).unwrap();
    assert!(huge_header.file_length > 1 << 20);
    let err = OpenOptions::new().max_unpacked_bytes(1 << 20).from_bytes(&huge).err().expect("opened").to_string();
    assert!(err.contains("more than the limit"), "{err}");
    // And streaming: unpack decodes to a file, so the claim costs no memory, and is refused.
    let path = dir.path().join("bomb.packed");
    std::fs::write(&path, &within).unwrap();
    let err = pack::unpack_path(&path, &dir.path().join("bomb.vlf"), &NoProgress).expect_err("unpacked").to_string();
    assert!(err.contains("does not decode") || err.contains("decodes to"), "{err}");
}

/// Without a caller's limit, a packed field is decoded into no more than the memory budget: a
/// claim past what the machine can give is refused before anything is allocated, naming the
/// limit, where it used to be allocated (lazily) and decoded until the frames ran out, or, backed
/// by frames, until the process was killed. A caller may still ask for more.
#[test]
fn a_claim_past_the_memory_budget_is_refused_by_default() {
    let budget = vlf_runtime::memory::budget();
    if !budget.is_reported() {
        eprintln!("skipped: this system reports neither its available memory nor an address-space limit");
        return;
    }
    // Random triangles compress poorly: about 36 stored bytes each, which may claim up to
    // MAX_ZSTD_EXPANSION times as many. Enough of them to claim twice the budget.
    let per_triangle = 36 * vlf_format::MAX_ZSTD_EXPANSION;
    let count = (2 * budget.bytes / per_triangle + 1000) as usize;
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::from_triangles("random", &generate::random_cube(count, 0.05, 7)).unwrap();
    let raw = bake(&scene, dir.path(), "random.vlf", 3, 1, DEFAULT_DEPTH);
    let bytes = std::fs::read(pack_at(&raw, 1)).unwrap();
    // Each compressed section claims the same share of its bound: in all, a quarter more than the
    // budget, which an allocator would grant (lazily) on most machines.
    let bounds: u64 = head(&bytes).1.iter().filter(|e| e.codec == codec::ZSTD).map(|e| e.stored_length).sum::<u64>()
        * vlf_format::MAX_ZSTD_EXPANSION;
    let share = (budget.bytes + budget.bytes / 4) as f64 / bounds as f64;
    assert!(share < 1.0, "{count} triangles cannot claim {} bytes", budget.bytes);
    let claim = with_table(&bytes, |t| {
        for e in t.iter_mut().filter(|e| e.codec == codec::ZSTD) {
            let el = e.element_size as u64;
            e.raw_length = (e.stored_length as f64 * vlf_format::MAX_ZSTD_EXPANSION as f64 * share) as u64 / el * el;
        }
    });
    let (claim_header, _) = vlf_format::pack::unpacked_layout(&head(&claim).0, &head(&claim).1).unwrap();
    assert!(claim_header.file_length > budget.bytes, "{} ≤ {}", claim_header.file_length, budget.bytes);
    match Field::from_bytes(&claim) {
        Err(OpenError::Bytes(FormatError::UnpackedTooLarge { bytes, limit })) => {
            assert_eq!(bytes, claim_header.file_length);
            // The budget moves while other processes run; it was read again at open.
            assert!(limit < bytes && limit > budget.bytes / 2, "limit {limit}, budget {budget:?}");
        }
        other => panic!("a claim of {} bytes: {:?}", claim_header.file_length, other.err()),
    }
    let said = Field::from_bytes(&claim).err().unwrap().to_string();
    assert!(said.contains("more than the limit") && said.contains("vlf-bake unpack"), "{said}");
    // Asked for, the claim gets past the limit to the decoder, which finds the frames do not back
    // it (or to an allocation that fails): never the limit's error.
    match OpenOptions::new().max_unpacked_bytes(u64::MAX).from_bytes(&claim) {
        Err(OpenError::Bytes(FormatError::Decode { .. } | FormatError::OutOfMemory { .. })) => {}
        other => panic!("{:?}", other.err()),
    }
    // The unchanged field opens with the defaults.
    Field::from_bytes(&bytes).expect("the packed field");
}

#[test]
fn packing_refuses_packed_damaged_and_non_canonical_inputs() {
    let (dir, packed, _) = tiny_packed();
    let out = dir.path().join("again.packed");
    let err = pack::pack_path(&packed, &out, 3, &NoProgress).expect_err("packed twice").to_string();
    assert!(err.contains("already packed"), "{err}");
    let raw = dir.path().join("box.vlf");
    let err = pack::unpack_path(&raw, &out, &NoProgress).expect_err("unpacked a raw field").to_string();
    assert!(err.contains("not packed"), "{err}");
    assert!(matches!(pack::pack_path(&raw, &out, 0, &NoProgress), Err(pack::PackError::Level(0))));

    // A flipped byte in a raw section's payload: the packer checks the hashes it reads.
    let raw_bytes = std::fs::read(&raw).unwrap();
    let (_, table) = head(&raw_bytes);
    let tiles = table.iter().find(|e| e.kind == SectionKind::Tiles as u32).unwrap();
    let mut damaged = raw_bytes.clone();
    damaged[tiles.offset as usize] ^= 1;
    let damaged_path = dir.path().join("damaged.vlf");
    std::fs::write(&damaged_path, &damaged).unwrap();
    let err = pack::pack_path(&damaged_path, &out, 3, &NoProgress).expect_err("packed a damaged field").to_string();
    assert!(err.contains("TILES"), "{err}");

    // The last section moved 64 bytes on: a valid field, but not one unpack could reproduce.
    let last = table.len() - 1;
    let mut moved = with_table(&raw_bytes, |t| t[last].offset += 64);
    let at = table[last].offset as usize;
    moved.splice(at..at, [0u8; 64]);
    let file_length = moved.len() as u64;
    moved[16..24].copy_from_slice(&file_length.to_le_bytes());
    rehash(&mut moved);
    Field::from_bytes(&moved).expect("a non-canonical field is still a field");
    let moved_path = dir.path().join("moved.vlf");
    std::fs::write(&moved_path, &moved).unwrap();
    let err = pack::pack_path(&moved_path, &out, 3, &NoProgress).expect_err("packed a moved field").to_string();
    assert!(err.contains("canonical"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_ray_through_a_packed_field_from_bytes_matches_the_box() {
    let (_dir, _, bytes) = tiny_packed();
    let field = Field::from_bytes(&bytes).unwrap();
    // The box spans [0,1]×[0,2]×[0,3]; a ray from outside along -z hits its top at z = 3.
    let hit = field.closest_hit(&Ray::new([0.5, 0.5, 10.0], [0.0, 0.0, -1.0])).unwrap();
    assert_eq!(hit.t, 7.0);
}

/// Packing is generic over section kinds (§8.2): a field of a later minor version with a kind this
/// code does not know packs, opens and unpacks byte for byte, the unknown section included.
#[test]
fn unknown_section_kinds_and_minor_versions_survive_packing() {
    let dir = tempfile::tempdir().unwrap();
    let raw = bake(&mesh("bunny.obj"), dir.path(), "bunny.vlf", 33, 16, DEFAULT_DEPTH);
    let bytes = std::fs::read(&raw).unwrap();
    let (mut header, table) = head(&bytes);
    let mut sections: Vec<Vec<u8>> =
        table.iter().map(|e| bytes[e.offset as usize..(e.offset + e.stored_length) as usize].to_vec()).collect();
    let extra: Vec<u8> = (0..40_000u32).flat_map(|i| (i % 97).to_le_bytes()).collect();
    let mut table = table.clone();
    table.push(SectionEntry {
        kind: 0x7000,
        codec: codec::RAW,
        offset: 0,
        stored_length: extra.len() as u64,
        raw_length: extra.len() as u64,
        element_size: 4,
        reserved: 0,
        raw_hash: *blake3::hash(&extra).as_bytes(),
    });
    sections.push(extra);
    header.version_minor = 7;
    let header = vlf_format::pack::lay_out(&header, &mut table).unwrap();
    let mut future = vlf_format::pack::head_bytes(&header, &table);
    for (e, section) in table.iter().zip(&sections) {
        future.resize(e.offset as usize, 0);
        future.extend_from_slice(section);
    }
    let future_path = dir.path().join("future.vlf");
    std::fs::write(&future_path, &future).unwrap();
    Field::open(&future_path).expect("a reader skips kinds it does not know");

    let packed = pack_at(&future_path, 3);
    let packed_bytes = std::fs::read(&packed).unwrap();
    let (packed_header, packed_table) = head(&packed_bytes);
    assert_eq!(packed_header.version_minor, 7);
    let unknown = packed_table.iter().find(|e| e.kind == 0x7000).expect("the unknown section is kept");
    assert_eq!(unknown.codec, codec::ZSTD, "the unknown section is compressed like any other");
    let field = Field::open(&packed).unwrap();
    assert!(field.is_packed() && field.reader().bytes == &future[..]);
    let back = dir.path().join("back.vlf");
    pack::unpack_path(&packed, &back, &NoProgress).unwrap();
    assert!(std::fs::read(&back).unwrap() == future, "unpack did not restore the future field");
}
