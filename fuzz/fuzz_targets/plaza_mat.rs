//! Fuzz target `plaza_mat`: see `fathom_fuzz::plaza_mat` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::plaza_mat(data);
});
