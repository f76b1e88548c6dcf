//! Fuzz target `import_obj`: see `vlf_tests::fuzz::import_obj` and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| vlf_tests::fuzz::import_obj(data));
