//! Fuzz target `map_stl`: see `fathom_fuzz::map_stl` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::map_stl(data);
});
