//! The fuzz binaries' allocator: the system allocator with a cap on the live Rust heap,
//! so that an input which makes fathom allocate beyond it is a crash libFuzzer keeps
//! (the allocation fails, Rust prints "memory allocation of N bytes failed" and aborts)
//! instead of passing unnoticed or taking the machine's memory.
//!
//! Compiled only into the cargo-fuzz binaries (`--cfg fuzzing`): the e2e test that
//! replays the corpora includes `lib.rs` as a module and keeps the test's allocator.
//! The cap is on the wrapped allocator's live bytes (`cap::Cap`); libFuzzer's own
//! memory is C++ heap outside it and bounded by `-rss_limit_mb` (see `.ci/fuzz.sh`).

use cap::Cap;
use std::alloc::System;

/// The most live Rust heap a fuzz input may use: 256 MiB.
///
/// Far above what the checked readers need for a fuzz input (the mesh readers refuse
/// files over 4 MiB, the MAT reader inflates at most 64 MiB, `fathom check` builds no
/// experiment state), far below a CI machine's memory.
pub const HEAP_CAP_BYTES: usize = 256 * 1024 * 1024;

#[global_allocator]
static ALLOCATOR: Cap<System> = Cap::new(System, HEAP_CAP_BYTES);
