//! Fuzz target `import_gltf`: see `vlf_tests::fuzz::import_gltf` and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| vlf_tests::fuzz::import_gltf(data));
