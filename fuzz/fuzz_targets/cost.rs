//! Fuzz target `cost`: see `fathom_fuzz::cost` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::cost(data);
});
