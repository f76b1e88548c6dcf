//! Replays every input of the fuzz corpora through the fuzz targets' code (`vlf_tests::fuzz`), so
//! the targets cannot rot and no bug the fuzzer found can come back: the committed seed corpus
//! (`fuzz/corpus/<target>/`) and every crash, timeout or out-of-memory input found so far
//! (`fixtures/fuzz-regressions/<target>/`, each named after what it caught). `docs/fuzzing.md`
//! says how to run the fuzzer itself.

#![forbid(unsafe_code)]

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The files directly under `dir`, sorted; none if it does not exist.
fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut files: Vec<PathBuf> = entries.map(|e| e.expect("directory entry").path()).filter(|p| p.is_file()).collect();
    files.sort();
    files
}

/// Runs `target` on every seed and regression input; fails naming each input that panics.
fn replay(name: &str, target: fn(&[u8])) -> usize {
    let seeds = files(&root().join("fuzz/corpus").join(name));
    let regressions = files(&root().join("fixtures/fuzz-regressions").join(name));
    assert!(!seeds.is_empty(), "the seed corpus fuzz/corpus/{name} is missing");
    let mut failed = Vec::new();
    for path in seeds.iter().chain(&regressions) {
        let bytes = std::fs::read(path).unwrap();
        if std::panic::catch_unwind(|| target(&bytes)).is_err() {
            failed.push(path.display().to_string());
        }
    }
    assert!(failed.is_empty(), "{name}: these inputs panic:\n{}", failed.join("\n"));
    seeds.len() + regressions.len()
}

#[test]
fn field_open_corpus() {
    replay("field_open", vlf_tests::fuzz::field_open);
}

#[test]
fn field_resealed_corpus() {
    replay("field_resealed", vlf_tests::fuzz::field_resealed);
}

#[test]
fn import_obj_corpus() {
    replay("import_obj", vlf_tests::fuzz::import_obj);
}

#[test]
fn import_gltf_corpus() {
    replay("import_gltf", vlf_tests::fuzz::import_gltf);
}

/// The field seeds are valid fields (so the fuzzer starts past the open checks): each opens and
/// passes `dump --verify`'s checks. A format change that breaks them must regenerate them
/// (`docs/fuzzing.md`).
#[test]
fn field_seeds_open_and_verify() {
    for name in ["field_open", "field_resealed"] {
        for path in files(&root().join("fuzz/corpus").join(name)) {
            let bytes = std::fs::read(&path).unwrap();
            let length = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
            let field =
                vlf_runtime::Field::from_bytes(&bytes[..length]).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            vlf_bake::inspect::verify(field.reader(), &mut |_, _| {})
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}

/// The mesh seeds not named `bad-*` import (the bytes after a NUL are the second file).
#[test]
fn mesh_seeds_import() {
    for (name, extension) in [("import_obj", "obj"), ("import_gltf", "gltf")] {
        for path in files(&root().join("fuzz/corpus").join(name)) {
            if path.file_name().unwrap().to_string_lossy().starts_with("bad-") {
                continue;
            }
            let bytes = std::fs::read(&path).unwrap();
            let glb = bytes.starts_with(b"glTF");
            let (main, second) = match bytes.iter().position(|&b| b == 0) {
                Some(i) if !glb => (&bytes[..i], bytes[i + 1..].to_vec()),
                _ => (&bytes[..], Vec::new()),
            };
            let mut builder = vlf_bake::SceneBuilder::new();
            let file = Path::new("seed").with_extension(if glb { "glb" } else { extension });
            vlf_bake::import::import_bytes(&mut builder, &file, main, &|_| Ok(second.clone()))
                .and_then(|()| builder.finish())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
}
