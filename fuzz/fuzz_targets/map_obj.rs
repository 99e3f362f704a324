//! Fuzz target `map_obj`: see `fathom_fuzz::map_obj` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::map_obj(data);
});
