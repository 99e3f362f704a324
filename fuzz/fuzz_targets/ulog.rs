//! Fuzz target `ulog`: see `fathom_fuzz::ulog` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::ulog(data);
});
