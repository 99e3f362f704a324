//! Fuzz target `selftest`: the negative controls of `.ci/fuzz.sh`, never fuzzed. An
//! input starting with `panic` panics, one starting with `alloc` asks for one byte more
//! than the heap cap (`fathom_fuzz::heap_cap`); CI runs the binary on each and requires
//! it to fail, so the fuzz step is known to catch a panic and an allocation over the cap.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if data.starts_with(b"panic") {
        panic!("selftest: a panic must fail the fuzz run");
    }
    if data.starts_with(b"alloc") {
        let over_cap = vec![1u8; fathom_fuzz::heap_cap::HEAP_CAP_BYTES + 1];
        std::hint::black_box(&over_cap);
    }
});
