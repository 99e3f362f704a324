//! Fuzz target `scenario_edit`: see `fathom_fuzz::scenario_edit` in ../src/lib.rs and docs/fuzzing.md.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fathom_fuzz::scenario_edit(data);
});
