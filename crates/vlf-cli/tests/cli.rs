//! End-to-end tests of the `vlf-bake` command line: the real binary, run as a user would, in
//! temporary directories, its outputs checked against the formats (`formats/rays.md`) and the
//! `vlf_runtime` library.
//!
//! Every run goes through `common::run`, which also asserts that the process was not killed by a
//! signal and that nothing it printed contains "panicked". Bakes use small explicit parameters
//! (`common::SMALL`) so each takes a few hundredths of a second.

#![forbid(unsafe_code)]

mod common;

use common::{Run, SMALL, command, mesh, names_in, run, s, tempdir, vlf};
use serde_json::{Value, json};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use vlf_runtime::{Field, Hit, Ray, hex};

const BUNNY_TRIANGLES: u64 = 3674;
const BOX_TRIANGLES: u64 = 12;

/// The sections every version 2 field holds (`formats/vlf.md` §5); the bunny has no others.
const SECTION_NAMES: [&str; 14] = [
    "SCENE",
    "PARAMS",
    "DIRECTIONS",
    "ROTATIONS",
    "LOOKUP",
    "BEAMS",
    "TILES",
    "LEAVES",
    "TRIANGLES",
    "PROVENANCE",
    "SOURCES",
    "INPUTS",
    "STRINGS",
    "STATISTICS",
];

/// Runs `vlf-bake bake INPUTS... -o OUTPUT --directions 33 --tiles 16 EXTRA...`.
fn bake(inputs: &[&Path], output: &Path, extra: &[&str]) -> Run {
    run(command().arg("bake").args(inputs).arg("-o").arg(output).args(SMALL).args(extra))
}

/// Bakes the bunny with `SMALL` parameters into `dir/name`.
fn bake_bunny(dir: &Path, name: &str) -> PathBuf {
    let field = dir.join(name);
    let r = bake(&[&mesh("bunny.obj")], &field, &["--quiet"]).ok();
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), ("", ""));
    field
}

/// `dump --json` of a field.
fn dump_json(field: &Path) -> Value {
    vlf(&["dump", s(field), "--json"]).ok().json()
}

/// The `(offset, stored_length)` of a section, from `dump --json`.
fn section_span(field: &Path, name: &str) -> (u64, u64) {
    let info = dump_json(field);
    let section = info["sections"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["name"] == name)
        .unwrap_or_else(|| panic!("no section {name} in dump --json"));
    (section["offset"].as_u64().unwrap(), section["stored_length"].as_u64().unwrap())
}

/// Asserts that no temporary file (`.NAME.XXXX.tmp`) was left in `dir`.
fn assert_no_temp_files(dir: &Path) {
    let names = names_in(dir);
    assert!(
        !names.iter().any(|n| n.starts_with('.') || n.ends_with(".tmp")),
        "temporary files left in {}: {names:?}",
        dir.display()
    );
}

fn is_hex_hash(v: &Value) -> bool {
    v.as_str().is_some_and(|s| s.len() == 64 && s.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)))
}

fn le_f32(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap())
}

fn le_u32(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap())
}

/// Reads a rays file by the byte layout of `formats/rays.md` (not through the `Ray` struct).
fn read_rays(path: &Path) -> Vec<Ray> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(bytes.len() % 32, 0, "{} is not a whole number of 32-byte rays", path.display());
    bytes
        .chunks_exact(32)
        .map(|c| Ray {
            org: [le_f32(c, 0), le_f32(c, 1), le_f32(c, 2)],
            tmin: le_f32(c, 3),
            dir: [le_f32(c, 4), le_f32(c, 5), le_f32(c, 6)],
            tmax: le_f32(c, 7),
        })
        .collect()
}

/// Writes a rays file by the byte layout of `formats/rays.md`.
fn write_rays(path: &Path, rays: &[Ray]) {
    let mut bytes = Vec::with_capacity(rays.len() * 32);
    for r in rays {
        for x in [r.org[0], r.org[1], r.org[2], r.tmin, r.dir[0], r.dir[1], r.dir[2], r.tmax] {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// A hit record as its four little-endian words: `t` bits, `prim`, `u` bits, `v` bits.
type Record = [u32; 4];

/// Reads a hits file by the byte layout of `formats/rays.md`.
fn read_hits(path: &Path) -> Vec<Record> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(bytes.len() % 16, 0, "{} is not a whole number of 16-byte hits", path.display());
    bytes.chunks_exact(16).map(|c| [le_u32(c, 0), le_u32(c, 1), le_u32(c, 2), le_u32(c, 3)]).collect()
}

fn record(hit: Hit) -> Record {
    [hit.t.to_bits(), hit.prim, hit.u.to_bits(), hit.v.to_bits()]
}

const MISS: Record = [0x7f80_0000, u32::MAX, 0, 0];

/// Parses the number in `text` that follows `before` and ends at `after`.
fn number_between(text: &str, before: &str, after: &str) -> f64 {
    let start = text.find(before).unwrap_or_else(|| panic!("no `{before}` in {text}")) + before.len();
    let len = text[start..].find(after).unwrap_or_else(|| panic!("no `{after}` after `{before}` in {text}"));
    text[start..start + len].trim().parse().unwrap_or_else(|e| panic!("`{}` is not a number: {e}", &text[start..]))
}

// ---------------------------------------------------------------------------------------------
// 1. bake

#[test]
fn bake_prints_a_summary_with_counts_size_time_and_hashes() {
    let dir = tempdir();
    let field_path = dir.path().join("bunny.vlf");
    let r = bake(&[&mesh("bunny.obj")], &field_path, &[]).ok();
    assert_eq!(r.stderr, "", "explicit parameters: no choice note, and no progress bar off a terminal");

    let field = Field::open(&field_path).unwrap();
    let bytes = std::fs::metadata(&field_path).unwrap().len();
    let out = &r.stdout;
    assert!(out.contains(&format!("{BUNNY_TRIANGLES} triangles")), "{out}");
    assert!(out.contains("33 directions"), "{out}");
    assert!(out.contains("16² tiles"), "{out}");
    assert!(out.contains(&format!("({bytes} bytes)")), "{out}");
    let seconds = number_between(out, "bytes) in ", " s");
    assert!((0.0..60.0).contains(&seconds), "{out}");
    assert!(out.contains(&format!("content hash {}", hex(&field.content_hash()))), "{out}");
    assert!(out.contains(&format!("input hash   {}", hex(&field.input_hash()))), "{out}");
}

#[test]
fn bake_json_prints_one_object_with_the_summary() {
    let dir = tempdir();
    let field_path = dir.path().join("bunny.vlf");
    let r = bake(&[&mesh("bunny.obj")], &field_path, &["--json"]).ok();
    assert_eq!(r.stderr, "");
    assert_eq!(r.stdout.lines().count(), 1, "one line of JSON: {}", r.stdout);
    let j = r.json();
    assert!(j.is_object(), "{j}");
    for key in ["triangles", "directions", "tile_resolution", "bytes", "seconds", "content_hash", "input_hash"] {
        assert!(j.get(key).is_some(), "--json lacks `{key}`: {j}");
    }
    let field = Field::open(&field_path).unwrap();
    assert_eq!(j["triangles"], BUNNY_TRIANGLES);
    assert_eq!(j["directions"], 33);
    assert_eq!(j["tile_resolution"], 16);
    assert_eq!(j["bytes"], std::fs::metadata(&field_path).unwrap().len());
    assert_eq!(j["bytes"], field.len_bytes());
    assert!(j["seconds"].as_f64().is_some_and(|t| (0.0..60.0).contains(&t)), "{j}");
    assert_eq!(j["content_hash"], hex(&field.content_hash()));
    assert_eq!(j["input_hash"], hex(&field.input_hash()));
    assert!(is_hex_hash(&j["content_hash"]) && is_hex_hash(&j["input_hash"]), "{j}");
}

#[test]
fn bake_quiet_prints_nothing_on_success() {
    let dir = tempdir();
    // Explicit parameters.
    let explicit = dir.path().join("explicit.vlf");
    let r = bake(&[&mesh("bunny.obj")], &explicit, &["--quiet"]).ok();
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), ("", ""));
    assert_eq!(Field::open(&explicit).unwrap().triangle_count() as u64, BUNNY_TRIANGLES);

    // Automatic parameters: without --quiet the choice is explained on stderr; with it, nothing.
    let auto = dir.path().join("auto.vlf");
    let loud = vlf(&["bake", s(&mesh("Box.gltf")), "-o", s(&auto)]).ok();
    assert!(loud.stderr.contains("chose"), "automatic parameters are explained: {loud:?}");
    let r = vlf(&["bake", s(&mesh("Box.gltf")), "-o", s(&auto), "-q"]).ok();
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), ("", ""));
    assert_eq!(Field::open(&auto).unwrap().triangle_count() as u64, BOX_TRIANGLES);
}

#[test]
fn bake_of_several_inputs_makes_one_field_with_all_their_triangles() {
    let dir = tempdir();
    let field_path = dir.path().join("both.vlf");
    let j = bake(&[&mesh("bunny.obj"), &mesh("Box.gltf")], &field_path, &["--json"]).ok().json();
    assert_eq!(j["triangles"], BUNNY_TRIANGLES + BOX_TRIANGLES);

    let field = Field::open(&field_path).unwrap();
    assert_eq!(field.triangle_count() as u64, BUNNY_TRIANGLES + BOX_TRIANGLES);
    let inputs: Vec<(String, u64)> = dump_json(&field_path)["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| (i["name"].as_str().unwrap().to_string(), i["triangles"].as_u64().unwrap()))
        .collect();
    assert_eq!(inputs, [("bunny.obj".to_string(), BUNNY_TRIANGLES), ("Box.gltf".to_string(), BOX_TRIANGLES)]);
    let mut per_input = std::collections::BTreeMap::<&str, u64>::new();
    for id in 0..field.triangle_count() {
        *per_input.entry(field.provenance(id).expect("every triangle has a provenance").input).or_default() += 1;
    }
    assert_eq!(per_input, [("Box.gltf", BOX_TRIANGLES), ("bunny.obj", BUNNY_TRIANGLES)].into());
}

// ---------------------------------------------------------------------------------------------
// 2. dump

#[test]
fn dump_json_has_the_documented_keys_and_agrees_with_the_library() {
    let dir = tempdir();
    let field_path = bake_bunny(dir.path(), "bunny.vlf");
    let r = vlf(&["dump", s(&field_path), "--json"]).ok();
    assert_eq!(r.stderr, "");
    let j = r.json();
    for key in [
        "format_version",
        "content_hash",
        "input_hash",
        "triangle_count",
        "direction_count",
        "tile_resolution",
        "file_bytes",
        "sections",
        "statistics",
        "worst_direction_angle_deg",
    ] {
        assert!(j.get(key).is_some(), "dump --json lacks `{key}`: {j}");
    }
    assert!(j.get("verify").is_none(), "no verify object without --verify");

    let field = Field::open(&field_path).unwrap();
    assert_eq!(j["format_version"], "2.0");
    assert_eq!((&j["materials"], &j["cameras"], &j["lights"]), (&json!(0), &json!(0), &json!(0)), "{j}");
    assert_eq!(j["content_hash"], hex(&field.content_hash()));
    assert_eq!(j["input_hash"], hex(&field.input_hash()));
    assert_eq!(j["triangle_count"], field.triangle_count());
    assert_eq!(j["direction_count"], field.direction_count());
    assert_eq!(j["tile_resolution"], field.tile_resolution());
    assert_eq!(j["file_bytes"], field.len_bytes());
    assert_eq!(j["file_bytes"], std::fs::metadata(&field_path).unwrap().len());
    assert_eq!((field.direction_count(), field.tile_resolution()), (33, 16));

    let sections = j["sections"].as_array().expect("sections is an array");
    assert_eq!(sections.len(), 14, "{j}");
    let file_bytes = field.len_bytes();
    for e in sections {
        for key in ["name", "offset", "stored_length", "raw_hash"] {
            assert!(e.get(key).is_some(), "section lacks `{key}`: {e}");
        }
        let (offset, len) = (e["offset"].as_u64().unwrap(), e["stored_length"].as_u64().unwrap());
        assert!(offset + len <= file_bytes, "section outside the file: {e}");
        assert!(is_hex_hash(&e["raw_hash"]), "{e}");
    }
    let mut names: Vec<&str> = sections.iter().map(|e| e["name"].as_str().unwrap()).collect();
    names.sort_unstable();
    let mut expected = SECTION_NAMES;
    expected.sort_unstable();
    assert_eq!(names, expected);

    assert!(j["statistics"].is_object(), "{j}");
    assert_eq!(j["statistics"]["tiles"], 33 * 16 * 16);
    let angle = j["worst_direction_angle_deg"].as_f64().expect("a number");
    assert!(angle > 0.0 && angle < 90.0, "{angle}");
}

#[test]
fn dump_text_describes_the_field_and_names_every_section() {
    let dir = tempdir();
    let field_path = bake_bunny(dir.path(), "bunny.vlf");
    let r = vlf(&["dump", s(&field_path)]).ok();
    assert_eq!(r.stderr, "");
    let field = Field::open(&field_path).unwrap();
    assert!(r.stdout.starts_with("VLF field, format 2.0"), "{}", r.stdout);
    assert!(r.stdout.contains("0 materials, 0 cameras, 0 lights"), "{}", r.stdout);
    assert!(r.stdout.contains(&hex(&field.content_hash())), "{}", r.stdout);
    assert!(r.stdout.contains(&format!("{BUNNY_TRIANGLES}")), "{}", r.stdout);
    for name in SECTION_NAMES {
        assert!(r.stdout.contains(name), "dump does not mention section {name}:\n{}", r.stdout);
    }
    assert!(!r.stdout.contains("verify"), "no verification without --verify");
}

#[test]
fn dump_verify_reports_ok_on_a_sound_field() {
    let dir = tempdir();
    let field_path = bake_bunny(dir.path(), "bunny.vlf");
    let r = vlf(&["dump", s(&field_path), "--verify"]).ok();
    assert_eq!(r.stderr, "");
    assert!(r.stdout.contains("verify: OK"), "{}", r.stdout);

    let j = vlf(&["dump", s(&field_path), "--verify", "--json"]).ok().json();
    assert_eq!(j["verify"]["ok"], true, "{j}");
    assert_eq!(j["verify"]["triangle_ids"], j["statistics"]["triangle_ids"], "{j}");
}

// ---------------------------------------------------------------------------------------------
// 3. corruption

#[test]
fn a_flipped_byte_in_the_leaves_fails_verify_naming_the_section() {
    let dir = tempdir();
    let good = bake_bunny(dir.path(), "good.vlf");
    let (offset, len) = section_span(&good, "LEAVES");
    assert!(len > 0);
    let mut bytes = std::fs::read(&good).unwrap();
    bytes[(offset + len / 2) as usize] ^= 0x01;
    let bad = dir.path().join("bad.vlf");
    std::fs::write(&bad, &bytes).unwrap();

    // Opening checks only the header and table (O(1)), so a plain dump still describes it...
    vlf(&["dump", s(&bad)]).ok();
    // ...and --verify finds the damaged section.
    for args in [vec!["dump", s(&bad), "--verify"], vec!["dump", s(&bad), "--verify", "--json"]] {
        let r = vlf(&args);
        let line = r.one_error_line();
        assert!(line.contains("LEAVES"), "the error does not name the section: {line}");
        assert!(line.contains("hash mismatch") || line.contains("corrupt"), "{line}");
        assert!(!r.stdout.contains("verify: OK"), "{}", r.stdout);
    }
}

#[test]
fn a_flipped_byte_in_the_header_is_a_content_hash_mismatch_at_open() {
    let dir = tempdir();
    let good = bake_bunny(dir.path(), "good.vlf");
    let mut bytes = std::fs::read(&good).unwrap();
    bytes[90] ^= 0x10; // inside the header's input hash (bytes 80..112)
    let bad = dir.path().join("bad.vlf");
    std::fs::write(&bad, &bytes).unwrap();
    for args in [vec!["dump", s(&bad)], vec!["dump", s(&bad), "--json"], vec!["dump", s(&bad), "--verify"]] {
        let r = vlf(&args);
        let line = r.one_error_line();
        assert!(line.contains("content hash mismatch"), "{line}");
        assert!(line.contains("bad.vlf"), "the error does not name the file: {line}");
        if args.contains(&"--json") {
            // With --json the failure is also one JSON object on standard output.
            assert_eq!(r.json(), serde_json::json!({ "error": &line["error: ".len()..] }));
        } else {
            assert_eq!(r.stdout, "");
        }
    }
}

#[test]
fn a_truncated_field_is_refused() {
    let dir = tempdir();
    let good = bake_bunny(dir.path(), "good.vlf");
    let bytes = std::fs::read(&good).unwrap();
    for (name, len) in [("cut_end.vlf", bytes.len() - 100), ("cut_half.vlf", bytes.len() / 2), ("cut_header.vlf", 50)] {
        let bad = dir.path().join(name);
        std::fs::write(&bad, &bytes[..len]).unwrap();
        let rays = dir.path().join("rays.bin");
        for args in [vec!["dump", s(&bad)], vec!["dump", s(&bad), "--verify"], vec!["rays", s(&bad), "-o", s(&rays)]] {
            let r = vlf(&args);
            let line = r.one_error_line();
            assert!(line.contains("truncated"), "{line}");
            assert!(line.contains(name), "{line}");
        }
    }
}

#[test]
fn a_foreign_file_is_not_a_vlf_field() {
    let dir = tempdir();
    let hits = dir.path().join("hits.bin");
    for foreign in [mesh("bunny.obj"), mesh("Box.gltf"), mesh("bunny_scene.glb")] {
        for args in [
            vec!["dump", s(&foreign)],
            vec!["dump", s(&foreign), "--verify"],
            vec!["trace", s(&foreign), "--rays", s(&foreign), "-o", s(&hits)],
        ] {
            let r = vlf(&args);
            let line = r.one_error_line();
            assert!(line.contains("not a VLF field"), "{line}");
        }
    }
    assert!(!hits.exists(), "no hits file for a failed trace");
}

#[test]
fn error_messages_do_not_repeat_their_cause() {
    let dir = tempdir();
    let good = bake_bunny(dir.path(), "good.vlf");
    let mut bytes = std::fs::read(&good).unwrap();
    bytes[90] ^= 0x10;
    let bad = dir.path().join("bad.vlf");
    std::fs::write(&bad, &bytes).unwrap();
    let missing = dir.path().join("missing.vlf");
    let cases = [
        (vlf(&["dump", s(&bad)]), "content hash mismatch"),
        (vlf(&["dump", s(&mesh("bunny.obj"))]), "not a VLF field"),
        (vlf(&["dump", s(&missing)]), "(os error 2)"),
        (bake(&[&dir.path().join("missing.obj")], &dir.path().join("x.vlf"), &[]), "(os error 2)"),
        (bake(&[&mesh("Box.gltf")], &dir.path().join("no/such/dir/x.vlf"), &[]), "(os error 2)"),
    ];
    for (r, phrase) in cases {
        let line = r.one_error_line();
        assert_eq!(line.matches(phrase).count(), 1, "`{}` repeats `{phrase}`: {line}", r.what);
    }
}

#[test]
fn dump_of_a_field_with_corrupt_statistics_reports_instead_of_panicking() {
    let dir = tempdir();
    let good = bake_bunny(dir.path(), "good.vlf");
    let (offset, _) = section_span(&good, "STATISTICS");
    let offset = offset as usize;
    // StatisticsRecord: tile_count u64 @0, empty_tiles u64 @8, ..., depth_histogram [u64; 32] @48.
    let mut histogram = std::fs::read(&good).unwrap();
    histogram[offset + 48 + 31 * 8..offset + 48 + 32 * 8].copy_from_slice(&u64::MAX.to_le_bytes());
    let mut empty = std::fs::read(&good).unwrap();
    empty[offset + 8..offset + 16].copy_from_slice(&u64::MAX.to_le_bytes());
    for (name, bytes) in [("histogram.vlf", histogram), ("empty.vlf", empty)] {
        let bad = dir.path().join(name);
        std::fs::write(&bad, bytes).unwrap();
        // `run` fails the test if the process panics. Open does not hash STATISTICS, so a plain
        // dump may describe the nonsense, but it must not crash; --verify must name the section.
        let plain = vlf(&["dump", s(&bad)]);
        assert!(plain.code == 0 || plain.code == 1, "{plain:?}");
        let r = vlf(&["dump", s(&bad), "--verify"]);
        let line = r.one_error_line();
        assert!(line.contains("STATISTICS"), "{line}");
    }
}

// ---------------------------------------------------------------------------------------------
// 4. determinism and atomic output

#[test]
fn bakes_are_byte_identical_for_any_thread_count() {
    let dir = tempdir();
    let inputs = [mesh("bunny.obj"), mesh("Box.gltf")];
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let one = dir.path().join("one.vlf");
    let two = dir.path().join("two.vlf");
    let env = dir.path().join("env.vlf");
    bake(&inputs, &one, &["--threads", "1", "-q"]).ok();
    bake(&inputs, &two, &["--threads", "2", "-q"]).ok();
    run(command().env("RAYON_NUM_THREADS", "3").arg("bake").args(&inputs).arg("-o").arg(&env).args(SMALL).arg("-q"))
        .ok();
    let reference = std::fs::read(&one).unwrap();
    assert!(std::fs::read(&two).unwrap() == reference, "--threads 1 and --threads 2 differ");
    assert!(std::fs::read(&env).unwrap() == reference, "--threads 1 and RAYON_NUM_THREADS=3 differ");
}

#[test]
fn baking_over_an_existing_field_replaces_it_atomically() {
    let dir = tempdir();
    let out = bake_bunny(dir.path(), "scene.vlf");
    let old = Field::open(&out).unwrap();
    let old_hash = old.content_hash();

    bake(&[&mesh("Box.gltf")], &out, &["-q"]).ok();
    let new = Field::open(&out).unwrap();
    assert_eq!(new.triangle_count() as u64, BOX_TRIANGLES);
    assert_ne!(new.content_hash(), old_hash);
    // The rename left the old mapping on the old file: it still reads as the bunny (an in-place
    // rewrite would have changed or truncated the mapped bytes under it).
    assert_eq!(old.triangle_count() as u64, BUNNY_TRIANGLES);
    assert_eq!(old.content_hash(), old_hash);
    assert!(old.closest_hit(&Ray::new([0.0, 4.8, 20.0], [0.0, 0.0, -1.0])).is_some());
    assert_eq!(names_in(dir.path()), ["scene.vlf"]);
    assert_no_temp_files(dir.path());
}

#[test]
fn a_failed_bake_leaves_the_previous_field_and_no_temporary_files() {
    let dir = tempdir();
    let out = bake_bunny(dir.path(), "scene.vlf");
    let before = std::fs::read(&out).unwrap();
    let missing = dir.path().join("missing.obj");
    let failures = [
        (bake(&[&missing], &out, &[]), "missing.obj"),
        (bake(&[&mesh("bad/nan_vertex.obj")], &out, &[]), "nan_vertex.obj"),
        (bake(&[&mesh("Box.gltf"), &mesh("bad/nan_vertex.obj")], &out, &[]), "non-finite"),
        (bake(&[&mesh("bad/empty.obj")], &out, &[]), "empty.obj"),
        (bake(&[&mesh("bunny.obj")], &out, &["--max-bytes", "1KiB"]), "budget"),
    ];
    for (r, phrase) in failures {
        let line = r.one_error_line();
        assert!(line.contains(phrase), "`{}`: {line}", r.what);
        assert!(std::fs::read(&out).unwrap() == before, "`{}` changed the previous field", r.what);
        assert_eq!(names_in(dir.path()), ["scene.vlf"], "after `{}`", r.what);
    }
    assert_no_temp_files(dir.path());
    vlf(&["dump", s(&out), "--verify"]).ok();
}

#[cfg(unix)]
#[test]
fn output_files_get_the_same_permissions_as_any_new_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempdir();
    let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    let reference = dir.path().join("reference");
    std::fs::write(&reference, b"").unwrap(); // honours the umask, as cp, cargo and compilers do
    let expected = mode(&reference);

    let field = bake_bunny(dir.path(), "bunny.vlf");
    let rays = dir.path().join("rays.bin");
    let hits = dir.path().join("hits.bin");
    let obj = dir.path().join("random.obj");
    vlf(&["rays", s(&field), "--width", "8", "--height", "8", "-o", s(&rays)]).ok();
    vlf(&["trace", s(&field), "--rays", s(&rays), "-o", s(&hits)]).ok();
    vlf(&["gen", "random", "--count", "10", "-o", s(&obj)]).ok();
    for p in [&field, &rays, &hits, &obj] {
        assert_eq!(mode(p), expected, "{} has mode {:o}, a new file gets {expected:o}", p.display(), mode(p));
    }
}

// ---------------------------------------------------------------------------------------------
// 5. rays and trace

/// Bakes the bunny and writes 64×48 primary rays from outside; returns (dir, field, rays).
fn bunny_and_rays() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let rays = dir.path().join("rays.bin");
    let r = vlf(&["rays", s(&field), "--view", "outside", "--width", "64", "--height", "48", "-o", s(&rays)]).ok();
    let summary = format!("wrote 3072 rays (64×48, outside view) to {}: 96.0 KiB (98304 bytes)\n", rays.display());
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), (summary.as_str(), ""));
    assert_eq!(std::fs::metadata(&rays).unwrap().len(), 64 * 48 * 32);
    (dir, field, rays)
}

#[test]
fn trace_closest_hits_match_the_library_bit_for_bit() {
    let (dir, field_path, rays_path) = bunny_and_rays();
    let hits_path = dir.path().join("hits.bin");
    let r = vlf(&["trace", s(&field_path), "--rays", s(&rays_path), "-o", s(&hits_path), "--json"]).ok();
    assert_eq!(r.stderr, "");
    let j = r.json();
    for key in ["rays", "hits", "seconds", "mrays_per_s"] {
        assert!(j.get(key).is_some(), "trace --json lacks `{key}`: {j}");
    }
    assert_eq!(j["rays"], 3072);
    assert_eq!(j["invalid"], 0);
    assert_eq!(j["any_hit"], false);
    assert!(j["seconds"].as_f64().is_some_and(|t| t >= 0.0) && j["mrays_per_s"].as_f64().is_some_and(|m| m > 0.0));

    let field = Field::open(&field_path).unwrap();
    let rays = read_rays(&rays_path);
    let hits = read_hits(&hits_path);
    assert_eq!((rays.len(), hits.len()), (3072, 3072));
    let mut hit_count = 0;
    for (i, (ray, got)) in rays.iter().zip(&hits).enumerate() {
        assert!(ray.is_valid(), "ray {i} from `rays` is invalid: {ray:?}");
        let expected = field.closest_hit(ray);
        hit_count += expected.is_some() as u64;
        assert_eq!(*got, record(Hit::record(expected)), "ray {i}: {ray:?}");
    }
    assert_eq!(j["hits"], hit_count);
    assert!(hit_count > 100 && hit_count < 3072, "the frame should show both the bunny and background: {hit_count}");

    // One worker thread: the same records.
    let hits1 = dir.path().join("hits1.bin");
    let j1 = vlf(&["trace", s(&field_path), "--rays", s(&rays_path), "-o", s(&hits1), "--json", "--threads", "1"])
        .ok()
        .json();
    assert_eq!(j1["threads"], 1);
    assert_eq!(j1["hits"], hit_count);
    assert!(std::fs::read(&hits1).unwrap() == std::fs::read(&hits_path).unwrap(), "--threads 1 differs");

    // Text output.
    let text = vlf(&["trace", s(&field_path), "--rays", s(&rays_path), "-o", s(&hits1)]).ok();
    assert!(text.stdout.starts_with(&format!("traced 3072 rays ({hit_count} hits, 0 invalid)")), "{}", text.stdout);
}

#[test]
fn trace_any_hit_agrees_with_the_library() {
    let (dir, field_path, rays_path) = bunny_and_rays();
    let field = Field::open(&field_path).unwrap();
    let rays = read_rays(&rays_path);
    for threads in [None, Some("1")] {
        let hits_path = dir.path().join("any.bin");
        let mut args =
            vec!["trace", s(&field_path), "--rays", s(&rays_path), "-o", s(&hits_path), "--any-hit", "--json"];
        if let Some(t) = threads {
            args.extend(["--threads", t]);
        }
        let j = vlf(&args).ok().json();
        assert_eq!(j["rays"], 3072);
        assert_eq!(j["any_hit"], true);
        let hits = read_hits(&hits_path);
        assert_eq!(hits.len(), rays.len());
        let mut hit_count = 0;
        for (i, (ray, got)) in rays.iter().zip(&hits).enumerate() {
            let expected = field.any_hit(ray);
            assert_eq!(got[1] != u32::MAX, expected, "ray {i} (threads {threads:?}): record {got:?}");
            if expected {
                hit_count += 1;
                // Some hit in the interval, on an existing triangle, with valid barycentrics.
                let (t, u, v) = (f32::from_bits(got[0]), f32::from_bits(got[2]), f32::from_bits(got[3]));
                assert!(got[1] < field.triangle_count(), "ray {i}: {got:?}");
                assert!(t >= ray.tmin && t <= ray.tmax, "ray {i}: t = {t}");
                assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0 + 1e-6, "ray {i}: u = {u}, v = {v}");
            } else {
                assert_eq!(*got, MISS, "ray {i}");
            }
        }
        assert_eq!(j["hits"], hit_count);
        assert!(hit_count > 0);
    }
}

#[test]
fn trace_refuses_a_rays_file_that_is_not_whole_records() {
    let (dir, field_path, rays_path) = bunny_and_rays();
    let rays = std::fs::read(&rays_path).unwrap();
    let odd = dir.path().join("odd.bin");
    std::fs::write(&odd, &rays[..100]).unwrap();
    let hits = dir.path().join("hits.bin");
    let r = vlf(&["trace", s(&field_path), "--rays", s(&odd), "-o", s(&hits)]);
    let line = r.one_error_line();
    assert!(line.contains("odd.bin") && line.contains("100 bytes"), "{line}");
    assert!(line.contains("not a multiple of the 32-byte"), "{line}");
    assert!(!hits.exists(), "no hits file after a refused rays file");

    // An empty rays file is zero whole records: an empty hits file.
    let empty = dir.path().join("empty.bin");
    std::fs::write(&empty, b"").unwrap();
    let j = vlf(&["trace", s(&field_path), "--rays", s(&empty), "-o", s(&hits), "--json"]).ok().json();
    assert_eq!(j["rays"], 0);
    assert_eq!(std::fs::metadata(&hits).unwrap().len(), 0);
}

#[test]
fn invalid_rays_are_written_as_misses_and_counted() {
    let dir = tempdir();
    let field_path = bake_bunny(dir.path(), "bunny.vlf");
    let field = Field::open(&field_path).unwrap();
    let (c, radius) = field.bounding_sphere();
    let centre = [c[0] as f32, c[1] as f32, c[2] as f32];
    let from_front = [centre[0], centre[1], centre[2] + 3.0 * radius as f32];
    let valid = Ray::new(from_front, [0.0, 0.0, -1.0]);
    let rays = [
        valid,
        Ray::new([f32::NAN, 0.0, 0.0], [0.0, 0.0, -1.0]),
        Ray::new(from_front, [0.0, 0.0, 0.0]),
        Ray::with_interval(from_front, [0.0, 0.0, -1.0], 5.0, 1.0),
        Ray::with_interval(from_front, [0.0, 0.0, -1.0], 0.0, f32::NAN),
    ];
    let expected_invalid = rays.iter().filter(|r| !r.is_valid()).count();
    assert_eq!(expected_invalid, 4);
    let rays_path = dir.path().join("hand.bin");
    write_rays(&rays_path, &rays);
    // The three invalid kinds named by the brief, as their own file.
    let three_path = dir.path().join("three.bin");
    write_rays(&three_path, &rays[..4]);

    for any_hit in [false, true] {
        let hits_path = dir.path().join("hits.bin");
        let mut args = vec!["trace", s(&field_path), "--rays", s(&three_path), "-o", s(&hits_path), "--json"];
        if any_hit {
            args.push("--any-hit");
        }
        let j = vlf(&args).ok().json();
        assert_eq!(j["rays"], 4);
        assert_eq!(j["invalid"], 3, "{j}");

        args[3] = s(&rays_path);
        let j = vlf(&args).ok().json();
        assert_eq!(j["invalid"], 4, "a NaN bound is invalid too: {j}");
        let hits = read_hits(&hits_path);
        assert_eq!(hits.len(), rays.len());
        for (i, got) in hits.iter().enumerate().skip(1) {
            assert_eq!(*got, MISS, "invalid ray {i} ({:?}), any_hit {any_hit}", rays[i]);
        }
        if any_hit {
            assert_eq!(hits[0][1] != u32::MAX, field.any_hit(&valid));
        } else {
            assert_eq!(hits[0], record(Hit::record(field.closest_hit(&valid))));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 6. errors and help

#[test]
fn a_missing_input_is_one_error_line_naming_the_file() {
    let dir = tempdir();
    let missing = dir.path().join("no_such_mesh.obj");
    let out = dir.path().join("out.vlf");
    let r = bake(&[&missing], &out, &[]);
    let line = r.one_error_line();
    assert!(line.contains("no_such_mesh.obj"), "{line}");
    assert_eq!(r.stdout, "");
    assert!(!out.exists());

    let r = vlf(&["dump", s(&dir.path().join("no_such_field.vlf"))]);
    assert!(r.one_error_line().contains("no_such_field.vlf"));
    let r = vlf(&["rays", s(&dir.path().join("no_such_field.vlf")), "-o", s(&dir.path().join("r.bin"))]);
    assert!(r.one_error_line().contains("no_such_field.vlf"));
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let r = vlf(&["trace", s(&field), "--rays", s(&dir.path().join("no_rays.bin")), "-o", s(&out)]);
    assert!(r.one_error_line().contains("no_rays.bin"));
}

#[test]
fn invalid_flags_are_refused_with_a_clear_message() {
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    let bunny = mesh("bunny.obj");
    let bake_with = |flags: &[&str]| run(command().arg("bake").arg(&bunny).arg("-o").arg(&out).args(flags));
    // Values out of range are command-line errors too (`conventions.rs` has every flag).
    for (flags, phrase) in [
        (&["--tiles", "0", "--directions", "33"][..], "--tiles must be between 1 and 65536, got 0"),
        (&["--directions", "0", "--tiles", "16"], "--directions must be between 3 and 33554433, got 0"),
        (&["--max-depth", "99", "--directions", "33", "--tiles", "16"], "--max-depth must be between 0 and 12, got 99"),
        (&["--threads", "0", "--directions", "33", "--tiles", "16"], "--threads must be between 1 and 1024, got 0"),
    ] {
        let r = bake_with(flags).fails_with(2);
        assert!(r.stderr.starts_with(&format!("error: {phrase}\n")), "`{}`: {}", r.what, r.stderr);
        assert!(!out.exists(), "`{}` wrote a field", r.what);
    }
    // Command-line errors: exit 2, clap's message and usage hint.
    let clap_errors = [
        (bake_with(&["--max-bytes", "banana"]), "banana"),
        (bake_with(&["--tiles", "many"]), "many"),
        (bake_with(&["--no-such-flag"]), "--no-such-flag"),
        (vlf(&["frobnicate"]), "frobnicate"),
        (vlf(&["bake", s(&bunny)]), "--output"),
        (vlf(&["gen", "spheres", "-o", s(&out)]), "spheres"),
        (vlf(&[] as &[&str]), "Usage"),
    ];
    for (r, phrase) in clap_errors {
        let r = r.fails_with(2);
        assert!(r.stderr.starts_with("error:") || r.stderr.starts_with("Bake triangle meshes"), "{:?}", r);
        assert!(r.stderr.contains(phrase), "`{}` does not mention `{phrase}`: {}", r.what, r.stderr);
        assert!(!out.exists());
    }
    // `rays` validates its size.
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let r = vlf(&["rays", s(&field), "--width", "0", "-o", s(&dir.path().join("r.bin"))]).fails_with(2);
    assert!(r.stderr.starts_with("error: --width must be between 1 and 65535, got 0\n"), "{}", r.stderr);
}

#[test]
fn explicit_parameters_over_the_budget_are_refused() {
    let dir = tempdir();
    let out = dir.path().join("out.vlf");
    let r = run(command().arg("bake").arg(mesh("bunny.obj")).arg("-o").arg(&out).args([
        "--max-bytes",
        "1KiB",
        "--directions",
        "2049",
        "--tiles",
        "128",
    ]));
    let line = r.one_error_line();
    assert!(line.contains("budget"), "{line}");
    assert!(line.contains("--max-bytes"), "{line}");
    assert!(!out.exists());
    assert_no_temp_files(dir.path());
}

#[test]
fn every_subcommand_has_help() {
    for args in [
        &["--help"][..],
        &["help"],
        &["bake", "--help"],
        &["dump", "--help"],
        &["trace", "--help"],
        &["rays", "--help"],
        &["render", "--help"],
        &["gen", "--help"],
        &["demo", "--help"],
        &["pack", "--help"],
        &["unpack", "--help"],
        &["help", "bake"],
        &["bake", "-h"],
    ] {
        let r = vlf(args).ok();
        assert!(r.stdout.contains("Usage:"), "`{}` prints no usage:\n{}", r.what, r.stdout);
        assert!(r.stdout.contains("--help"), "`{}`:\n{}", r.what, r.stdout);
    }
    let r = vlf(&["--help"]).ok();
    for sub in ["bake", "dump", "pack", "unpack", "trace", "rays", "render", "gen", "demo"] {
        assert!(r.stdout.contains(sub), "top-level help does not list `{sub}`:\n{}", r.stdout);
    }
    let v = vlf(&["--version"]).ok();
    assert!(v.stdout.starts_with("vlf-bake "), "{}", v.stdout);
}

// ---------------------------------------------------------------------------------------------
// 7. gen

#[test]
fn gen_random_is_deterministic_and_bakes() {
    let dir = tempdir();
    let a = dir.path().join("a.obj");
    let b = dir.path().join("b.obj");
    let c = dir.path().join("c.obj");
    for (path, seed) in [(&a, "3"), (&b, "3"), (&c, "4")] {
        let r = vlf(&["gen", "random", "--count", "500", "--seed", seed, "-o", s(path)]).ok();
        assert!(r.stdout.starts_with(&format!("generated 500 random triangles (seed {seed}) into ")), "{}", r.stdout);
        assert_eq!((r.stdout.lines().count(), r.stderr.as_str()), (1, ""));
    }
    let bytes = std::fs::read(&a).unwrap();
    assert!(std::fs::read(&b).unwrap() == bytes, "same seed, different files");
    assert!(std::fs::read(&c).unwrap() != bytes, "different seeds, same file");
    let field = dir.path().join("random.vlf");
    let j = bake(&[&a], &field, &["--json"]).ok().json();
    assert_eq!(j["triangles"].as_u64().unwrap() + j["dropped_degenerate"].as_u64().unwrap(), 500, "{j}");
    assert!(j["triangles"].as_u64().unwrap() > 490, "{j}");
    vlf(&["dump", s(&field), "--verify"]).ok();
    assert_no_temp_files(dir.path());
}

#[test]
fn gen_grid_and_slivers_bake() {
    let dir = tempdir();
    for (kind, count, triangles) in [("grid", "8", 8 * 8 * 2 * 4), ("slivers", "200", 200)] {
        let obj = dir.path().join(format!("{kind}.obj"));
        vlf(&["gen", kind, "--count", count, "--seed", "7", "-o", s(&obj)]).ok();
        let field = dir.path().join(format!("{kind}.vlf"));
        let j = bake(&[&obj], &field, &["--json"]).ok().json();
        let baked = j["triangles"].as_u64().unwrap();
        assert_eq!(baked + j["dropped_degenerate"].as_u64().unwrap(), triangles, "{kind}: {j}");
        assert!(baked > 0, "{kind}: {j}");
        vlf(&["dump", s(&field), "--verify"]).ok();
    }
}

// ---------------------------------------------------------------------------------------------
// 8. demo

#[test]
fn demo_bakes_verifies_and_traces() {
    // The bundled bunny with automatic parameters takes about a second in the test profile; the
    // box exercises the same steps in a fraction of that.
    let dir = tempdir();
    let out = dir.path().join("demo");
    let r = vlf(&["demo", "--input", s(&mesh("Box.gltf")), "--output-dir", s(&out)]).ok();
    assert!(r.stdout.contains("verify: OK"), "{}", r.stdout);
    assert_eq!(r.stdout.matches("traced").count(), 2, "{}", r.stdout);
    assert!(r.stdout.contains("rendered"), "{}", r.stdout);
    assert_eq!(names_in(&out), ["demo.png", "demo.vlf", "inside.hits", "inside.rays", "outside.hits", "outside.rays"]);
    let (width, height, _) = vlf_render::decode_png(&std::fs::read(out.join("demo.png")).unwrap()).unwrap();
    assert_eq!((width, height), (640, 480));
    assert_eq!(std::fs::metadata(out.join("outside.rays")).unwrap().len(), 512 * 512 * 32);
    assert_eq!(std::fs::metadata(out.join("inside.hits")).unwrap().len(), 512 * 512 * 16);
    assert_eq!(Field::open(out.join("demo.vlf")).unwrap().triangle_count() as u64, BOX_TRIANGLES);

    let r = vlf(&["demo", "--input", s(&dir.path().join("nothing.obj")), "--output-dir", s(&out)]);
    assert!(r.one_error_line().contains("nothing.obj"));

    // A demo that fails removes the output directories it created, and only those.
    let bad = mesh("bad/nan_vertex.obj");
    let created = dir.path().join("new/deeper");
    let r = vlf(&["demo", "--input", s(&bad), "--output-dir", s(&created)]);
    r.fails_saying(&["nan_vertex.obj"]);
    assert_eq!(names_in(dir.path()), ["demo"], "a failed demo left its directories behind");
    // An existing output directory stays, with what it held.
    let r = vlf(&["demo", "--input", s(&bad), "--output-dir", s(&out)]);
    r.fails_saying(&["nan_vertex.obj"]);
    assert_eq!(names_in(&out).len(), 6, "a failed demo changed an existing directory");
}

// ---------------------------------------------------------------------------------------------
// 8b. render

#[test]
fn render_writes_the_picture_and_the_work_picture_and_counts_rays_by_kind() {
    let dir = tempdir();
    let field = dir.path().join("cornell.vlf");
    bake(&[&mesh("cornell/cornell.obj")], &field, &["-q"]).ok();
    let (png, work) = (dir.path().join("cornell.png"), dir.path().join("work.png"));
    let r = vlf(&[
        "render",
        s(&field),
        "-o",
        s(&png),
        "--width",
        "40",
        "--height",
        "30",
        "--samples",
        "1",
        "--eye",
        "0,12,48",
        "--target",
        "0,12,0",
        "--fov",
        "38",
        "--work-image",
        s(&work),
        "--work",
        "tiles",
        "--json",
    ])
    .ok();
    assert_eq!(r.stderr, "");
    let j = r.json();
    for key in ["output", "width", "height", "seconds", "rays", "mrays_per_s", "work", "work_image", "camera", "lights"]
    {
        assert!(j.get(key).is_some(), "render --json lacks `{key}`: {j}");
    }
    let rays = &j["rays"];
    assert_eq!(rays["primary"], 40 * 30);
    let kinds = ["primary", "shadow", "reflection", "refraction"].map(|k| rays[k].as_u64().unwrap());
    assert_eq!(kinds.iter().sum::<u64>(), rays["total"].as_u64().unwrap(), "{j}");
    // The room has a mirror and a glass ball in view, and the default lights cast shadows.
    assert!(kinds[1] > 0 && kinds[2] > 0 && kinds[3] > 0, "{j}");
    assert_eq!(j["lights"], "default key and fill");
    assert_eq!(j["work_image"]["metric"], "tiles visited");
    for path in [&png, &work] {
        let (w, h, _) = vlf_render::decode_png(&std::fs::read(path).unwrap()).unwrap();
        assert_eq!((w, h), (40, 30), "{}", path.display());
    }
    assert_no_temp_files(dir.path());
}

#[test]
fn render_uses_the_fields_gltf_camera_and_lights_and_not_the_thread_count() {
    let dir = tempdir();
    let field = dir.path().join("cornell.vlf");
    bake(&[&mesh("cornell/cornell.gltf")], &field, &["-q"]).ok();
    let r = vlf(&["dump", s(&field)]).ok();
    assert!(r.stdout.contains("7 materials, 1 camera, 2 lights"), "{}", r.stdout);

    // The camera's aspect ratio (4:3) sets the height.
    let one = dir.path().join("one.png");
    let j = vlf(&["render", s(&field), "-o", s(&one), "--width", "48", "--samples", "1", "--threads", "1", "--json"])
        .ok()
        .json();
    assert_eq!((&j["width"], &j["height"]), (&json!(48), &json!(36)), "{j}");
    assert_eq!(j["camera"], "field camera 0 \"front\"");
    assert_eq!((&j["lights"], &j["light_count"]), (&json!("the field's"), &json!(2)), "{j}");
    let two = dir.path().join("two.png");
    vlf(&["render", s(&field), "-o", s(&two), "--width", "48", "--samples", "1", "--threads", "2", "-q"]).ok();
    assert_eq!(std::fs::read(&one).unwrap(), std::fs::read(&two).unwrap(), "the thread count changed the picture");

    let j =
        vlf(&["render", s(&field), "-o", s(&two), "--width", "32", "--view", "inside", "--default-lights", "--json"])
            .ok()
            .json();
    // One size flag keeps the aspect ratio: 4:3 without a field camera.
    assert_eq!((&j["camera"], &j["height"]), (&json!("inside (across the scene)"), &json!(24)), "{j}");
    assert_eq!(j["lights"], "default key and fill");

    let r = vlf(&["render", s(&field), "-o", s(&two), "--camera", "1"]).fails_with(1);
    assert!(r.one_error_line().contains("has 1 camera(s)"), "{}", r.stderr);
}

#[test]
fn render_refuses_bad_flags_with_a_clear_message() {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let out = dir.path().join("out.png");
    for (flags, code, says) in [
        (&["--eye", "1,2"][..], 2, "expected 3"),
        (&["--light", "0,0,0,-1"][..], 2, "intensity"),
        (&["--samples", "0"][..], 2, "--samples must be between 1 and 16, got 0"),
        (&["--bounces", "65"][..], 2, "--bounces must be between 0 and 64, got 65"),
        (&["--width", "0"][..], 2, "--width must be between 1 and 65535, got 0"),
        (&["--fov", "200", "--eye", "0,0,30"][..], 2, "--fov must be between 0 (excluded) and 180 (excluded), got 200"),
        (&["--eye", "0,0,30", "--target", "0,0,30"][..], 2, "--eye and --target are the same point"),
        (&["--view", "inside", "--camera", "0"][..], 2, "cannot be used with"),
    ] {
        let r = vlf(&[&["render", s(&field), "-o", s(&out)][..], flags].concat()).fails_with(code);
        assert!(r.stderr.contains(says), "{flags:?}: {}", r.stderr);
    }
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------------------------
// 9. broken pipe

/// The write end of a pipe whose read end is already closed: any write to it fails with EPIPE.
///
/// `Stdio::piped()` on the process under test and dropping our read end would race with the
/// process's first write (a small output fits the pipe buffer and succeeds if written first, so
/// the test would pass without exercising the broken pipe). Instead the pipe comes from a helper
/// process's standard input: the helper (`vlf-bake --version`, which never reads stdin) holds the
/// only read end and has exited before the process under test starts.
fn closed_pipe() -> Stdio {
    let mut helper = command()
        .arg("--version")
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn helper");
    let write_end = helper.stdin.take().expect("piped stdin");
    assert!(helper.wait().expect("wait for helper").success());
    Stdio::from(write_end)
}

#[test]
fn output_into_a_closed_pipe_is_success() {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let rays = dir.path().join("rays.bin");
    vlf(&["rays", s(&field), "--width", "8", "--height", "8", "-o", s(&rays)]).ok();
    let hits = dir.path().join("hits.bin");
    let (box_mesh, box_field) = (mesh("Box.gltf"), dir.path().join("box.vlf"));
    let cases: [&[&str]; 5] = [
        &["dump", s(&field)],
        &["dump", s(&field), "--json"],
        &["dump", s(&field), "--verify"],
        &["trace", s(&field), "--rays", s(&rays), "-o", s(&hits)],
        &["bake", s(&box_mesh), "-o", s(&box_field), "--directions", "3", "--tiles", "2"],
    ];
    for args in cases {
        let r = run(command().args(args).stdout(closed_pipe()));
        assert_eq!(r.code, 0, "`{}` into a closed pipe: {r:?}", r.what);
        assert_eq!(r.stderr, "", "`{}` into a closed pipe", r.what);
    }
    // The work behind the output was still done.
    assert_eq!(std::fs::metadata(&hits).unwrap().len(), 64 * 16);
    Field::open(&box_field).unwrap();
}

/// Writing to an existing path that is not a regular file (a FIFO here; `/dev/null` in practice)
/// writes through it and leaves it in place. An atomic rename over it would replace the node: an
/// earlier version did that to `/dev/null`.
#[cfg(unix)]
#[test]
fn outputs_that_are_fifos_are_written_through_not_replaced() {
    use std::io::Read;
    use std::os::unix::fs::FileTypeExt;
    let dir = tempdir();
    let field = dir.path().join("box.vlf");
    assert_eq!(bake(&[&mesh("Box.gltf")], &field, &[]).code, 0);
    let rays = dir.path().join("rays.bin");
    assert_eq!(
        vlf(&[
            OsStr::new("rays"),
            field.as_os_str(),
            OsStr::new("--width"),
            OsStr::new("8"),
            OsStr::new("--height"),
            OsStr::new("4"),
            OsStr::new("-o"),
            rays.as_os_str()
        ])
        .code,
        0
    );
    let fifo = dir.path().join("hits.fifo");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            std::fs::File::open(&fifo).unwrap().read_to_end(&mut bytes).unwrap();
            bytes.len()
        })
    };
    let traced = vlf(&[
        OsStr::new("trace"),
        field.as_os_str(),
        OsStr::new("--rays"),
        rays.as_os_str(),
        OsStr::new("-o"),
        fifo.as_os_str(),
    ]);
    assert_eq!(traced.code, 0, "{}", traced.stderr);
    // Checked before joining: had the FIFO been replaced, the reader would wait forever.
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO was replaced");
    assert_eq!(reader.join().unwrap(), 8 * 4 * 16, "one 16-byte hit record per ray through the FIFO");
    // A field needs positioned writes: baking into a FIFO is refused, naming the problem.
    let refused = bake(&[&mesh("Box.gltf")], &fifo, &[]);
    assert_eq!(refused.code, 1);
    assert!(refused.stderr.contains("not a regular file"), "{}", refused.stderr);
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
}

// ---------------------------------------------------------------------------------------------
// 9. pack and unpack

#[test]
fn pack_and_unpack_restore_the_field_byte_for_byte_and_summarise() {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let packed = dir.path().join("bunny.packed.vlf");
    let j = vlf(&["pack", s(&field), "-o", s(&packed), "--json"]).ok().json();
    for key in ["raw_bytes", "packed_bytes", "ratio", "seconds", "mb_per_s", "level", "sections"] {
        assert!(j.get(key).is_some(), "pack --json lacks `{key}`: {j}");
    }
    assert!(is_hex_hash(&j["content_hash"]) && is_hex_hash(&j["raw_content_hash"]), "{j}");
    assert_eq!(j["level"], 3);
    assert_eq!(j["packed_bytes"].as_u64().unwrap(), std::fs::metadata(&packed).unwrap().len());
    assert_eq!(j["raw_bytes"].as_u64().unwrap(), std::fs::metadata(&field).unwrap().len());
    assert!(j["ratio"].as_f64().unwrap() > 1.5, "{j}");
    assert_eq!(j["raw_content_hash"], hex(&Field::open(&field).unwrap().content_hash()));
    assert_eq!(j["sections"].as_array().unwrap().len(), 14);

    let back = dir.path().join("back.vlf");
    let u = vlf(&["unpack", s(&packed), "-o", s(&back), "--json"]).ok().json();
    assert_eq!(u["content_hash"], j["raw_content_hash"]);
    assert!(std::fs::read(&back).unwrap() == std::fs::read(&field).unwrap(), "unpack did not restore the field");

    let r = vlf(&["pack", s(&field), "-o", s(&packed), "--quiet"]).ok();
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), ("", ""));
    let r = vlf(&["unpack", s(&packed), "-o", s(&back), "-q"]).ok();
    assert_eq!((r.stdout.as_str(), r.stderr.as_str()), ("", ""));
    let r = vlf(&["pack", s(&field), "-o", s(&packed), "--level", "9"]).ok();
    assert!(r.stdout.contains("at zstd level 9") && r.stdout.contains("unpacks to"), "{}", r.stdout);
    assert_no_temp_files(dir.path());
}

#[test]
fn a_packed_field_dumps_verifies_and_traces_like_the_raw_one() {
    let (dir, field, rays) = bunny_and_rays();
    let packed = dir.path().join("bunny.packed.vlf");
    vlf(&["pack", s(&field), "-o", s(&packed), "-q"]).ok();
    let raw_info = dump_json(&field);
    let info = dump_json(&packed);
    assert_eq!(info["file_bytes"].as_u64().unwrap(), std::fs::metadata(&packed).unwrap().len());
    assert_eq!(info["packed"]["unpacked_bytes"], raw_info["file_bytes"]);
    assert_eq!(info["packed"]["unpacked_content_hash"], raw_info["content_hash"]);
    assert_ne!(info["content_hash"], raw_info["content_hash"]);
    assert_eq!(info["statistics"], raw_info["statistics"]);
    let tiles = info["sections"].as_array().unwrap().iter().find(|e| e["name"] == "TILES").unwrap();
    assert_eq!(tiles["codec"], "zstd");
    assert!(tiles["stored_length"].as_u64() < tiles["raw_length"].as_u64(), "{tiles}");
    assert!(raw_info.get("packed").is_none(), "a raw field's dump has no `packed` key");

    let text = vlf(&["dump", s(&packed)]).ok().stdout;
    assert!(text.contains("packed        zstd") && text.contains("unpacks to"), "{text}");
    assert!(text.contains(&format!("content hash {}", raw_info["content_hash"].as_str().unwrap())), "{text}");
    let verified = vlf(&["dump", s(&packed), "--verify"]).ok().stdout;
    assert!(verified.contains("verify: OK"), "{verified}");

    let (raw_hits, packed_hits) = (dir.path().join("raw.hits"), dir.path().join("packed.hits"));
    vlf(&["trace", s(&field), "--rays", s(&rays), "-o", s(&raw_hits)]).ok();
    vlf(&["trace", s(&packed), "--rays", s(&rays), "-o", s(&packed_hits)]).ok();
    assert!(std::fs::read(&raw_hits).unwrap() == std::fs::read(&packed_hits).unwrap());
}

#[test]
fn a_damaged_packed_field_is_refused_by_dump_verify_and_unpack_naming_the_fault() {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let packed = dir.path().join("bunny.packed.vlf");
    vlf(&["pack", s(&field), "-o", s(&packed), "-q"]).ok();
    let good = std::fs::read(&packed).unwrap();
    let (offset, len) = section_span(&packed, "TILES");
    let (strings_offset, strings_len) = section_span(&packed, "STRINGS");

    let mut payload = good.clone();
    payload[(offset + len / 2) as usize] ^= 0x20;
    let mut padding = good.clone();
    padding[(strings_offset + strings_len) as usize] = 1; // STRINGS is raw and short: padding follows
    let out = dir.path().join("out.vlf");
    for (damaged, says, open_catches) in [(payload, "TILES", true), (padding, "padding", false)] {
        let bad = dir.path().join("bad.vlf");
        std::fs::write(&bad, &damaged).unwrap();
        let dump = vlf(&["dump", s(&bad)]);
        if open_catches {
            assert!(dump.one_error_line().contains(says), "{}", dump.stderr);
        } else {
            dump.ok();
        }
        for args in [vec!["dump", s(&bad), "--verify"], vec!["unpack", s(&bad), "-o", s(&out)]] {
            let r = vlf(&args);
            let line = r.one_error_line();
            assert!(line.contains(says) && line.contains("bad.vlf"), "{line}");
        }
        assert!(!out.exists(), "a failed unpack wrote its output");
    }
    assert_no_temp_files(dir.path());
}

#[test]
fn pack_refuses_bad_levels_packed_inputs_and_unpack_raw_ones() {
    let dir = tempdir();
    let field = bake_bunny(dir.path(), "bunny.vlf");
    let packed = dir.path().join("bunny.packed.vlf");
    for level in ["--level=0", "--level=20", "--level=-1", "--level=x"] {
        let r = vlf(&["pack", s(&field), "-o", s(&packed), level]).fails_with(2);
        assert!(r.stderr.contains("--level"), "{}", r.stderr);
    }
    vlf(&["pack", s(&field), "-o", s(&packed), "-q"]).ok();
    let again = dir.path().join("again.vlf");
    let r = vlf(&["pack", s(&packed), "-o", s(&again)]);
    assert!(r.one_error_line().contains("already packed"), "{}", r.stderr);
    let r = vlf(&["unpack", s(&field), "-o", s(&again)]);
    assert!(r.one_error_line().contains("not packed"), "{}", r.stderr);
    assert!(!again.exists());
}

#[test]
fn a_scene_too_small_for_f32_rays_at_its_distance_is_drawn_and_warned_of_where_rays_are_world_space() {
    // One triangle 1 unit across at x = 10⁹, where f32 numbers are 64 apart: it bakes, but an
    // adversarial sweep found `render` and `rays` + `trace` hitting it with none of their rays,
    // silently. `render` now traces relative to the field's centre (or, with `--scene`, the
    // centre of the scene's content) and draws it, without a warning; `rays` writes world-space
    // rays (formats/rays.md) and still warns.
    let dir = tempdir();
    let obj = dir.path().join("far.obj");
    std::fs::write(&obj, "v 1e9 0 0\nv 1e9 1 0\nv 1e9 0 1\nf 1 2 3\n").unwrap();
    let field = dir.path().join("far.vlf");
    vlf(&["bake", s(&obj), "-o", s(&field), "-q"]).ok();
    let warning = format!(
        "warning: {}: the scene is 1.414e0 across and 1.000e9 from the origin, where the rays' f32 coordinates are \
         6.400e1 apart",
        field.display()
    );
    let png = dir.path().join("far.png");
    let r = vlf(&["render", s(&field), "-o", s(&png), "--width", "16", "--height", "16", "--background", "0,0,0"]).ok();
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    let (_, _, rgb) = vlf_render::decode_png(&std::fs::read(&png).unwrap()).unwrap();
    let drawn = rgb.chunks_exact(3).filter(|p| p.iter().any(|&c| c > 0)).count();
    // 26 of 256 show the same triangle at the origin; none did with world-space rays.
    assert!(drawn >= 20, "{drawn} of 256 pixels show the triangle");
    let rays = dir.path().join("far.bin");
    let r = vlf(&["rays", s(&field), "-o", s(&rays), "--width", "4", "--height", "4"]).ok();
    assert!(r.stderr.starts_with(&warning), "{}", r.stderr);
    // A scene file of instances is traced relative to the centre of its content too: drawn,
    // without a warning (it drew 0 pixels, with one, while its rays were world-space).
    let scene = dir.path().join("far.json");
    std::fs::write(&scene, r#"{ "instances": [ { "field": "far.vlf" } ] }"#).unwrap();
    let args = ["render", "--scene", s(&scene), "-o", s(&png), "--width", "16", "--height", "16"];
    let r = vlf(&[&args[..], &["--background", "0,0,0"]].concat()).ok();
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    let (_, _, rgb) = vlf_render::decode_png(&std::fs::read(&png).unwrap()).unwrap();
    let drawn_in_scene = rgb.chunks_exact(3).filter(|p| p.iter().any(|&c| c > 0)).count();
    assert!(drawn_in_scene >= 20, "{drawn_in_scene} of 256 pixels show the instance");
    // The bunny near the origin gets none.
    let bunny = dir.path().join("bunny.vlf");
    vlf(&["bake", s(&mesh("bunny.obj")), "-o", s(&bunny), "--directions", "9", "--tiles", "8", "-q"]).ok();
    let r = vlf(&["render", s(&bunny), "-o", s(&png), "--width", "16", "--height", "16"]).ok();
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
}
