//! Fuzz target `field_resealed`: see `vlf_tests::fuzz::field_resealed` and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| vlf_tests::fuzz::field_resealed(data));
