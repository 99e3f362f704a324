//! Fuzz target `plaza_text`: see `fathom_fuzz::plaza_text` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::plaza_text(data);
});
