//! Fuzz target `field_open`: see `vlf_tests::fuzz::field_open` and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| vlf_tests::fuzz::field_open(data));
