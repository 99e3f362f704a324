//! Run-time choice of the vector instruction set for the fixed-size Kalman kernels.
//!
//! The crate is built for the default `x86-64` target (SSE2). `dispatch` runs a
//! closure compiled a second time with AVX2 enabled (through `pulp`, which `faer`
//! already uses) when the CPU has it, and hands the closure the instruction set
//! (`lanes::Isa`, private), so the `#[inline(always)]` kernels of `linalg` inlined
//! into it do their column chunks with 4-wide vectors (measured: the 6-state /
//! 3-measurement step ~10 % faster, the 9 / 3 step ~15 %; explicit chunks another
//! ~5 %, see `docs/performance.md`). Rust never fuses a
//! multiply and an add on its own and the compiler vectorizes only independent
//! lanes, so both versions perform the same IEEE operations in the same order:
//! results are bit-identical on every CPU (a test compares them, and CI runs it on
//! the optimized build).
//!
//! `FATHOM_SIMD=baseline` in the environment (read once, at the first filter step)
//! keeps the baseline version: for tools that do not know every AVX2 encoding
//! (valgrind 3.19 stops at a register-to-register `vmovq`), or to check a result
//! on the baseline path.

use std::sync::OnceLock;

use crate::lanes::Isa;

/// The AVX2 token when this CPU has AVX2 (and `FATHOM_SIMD=baseline` is not set),
/// found at first use (one atomic load afterwards).
#[cfg(target_arch = "x86_64")]
fn avx2() -> Option<pulp::x86::V3> {
    static AVX2: OnceLock<Option<pulp::x86::V3>> = OnceLock::new();
    #[cfg(test)]
    if tests::FORCE_BASELINE.with(std::cell::Cell::get) {
        return None;
    }
    *AVX2.get_or_init(|| {
        if std::env::var_os("FATHOM_SIMD").is_some_and(|v| v == "baseline") {
            None
        } else {
            pulp::x86::V3::try_new()
        }
    })
}

/// Runs `f` compiled for the widest instruction set this CPU has, and hands it that
/// instruction set for the explicit-lane kernels ([`Isa`]). Only what is inlined
/// into `f` benefits: the kernels are `#[inline(always)]`, and so must be the
/// closure (`#[inline(always)] |isa| ...`), or it stays a baseline function.
#[inline(always)]
pub(crate) fn dispatch<R>(f: impl FnOnce(Isa) -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = avx2() {
        return simd.vectorize(
            #[inline(always)]
            move || f(Isa::Avx2(simd)),
        );
    }
    f(Isa::Portable)
}

/// The instruction set the Kalman kernels run with on this machine: `"avx2"` or
/// `"baseline"` (SSE2 on x86-64; the only one on other architectures).
pub fn kernel_instruction_set() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    if avx2().is_some() {
        return "avx2";
    }
    "baseline"
}

#[cfg(test)]
pub(crate) mod tests {
    use std::cell::Cell;

    thread_local! {
        /// Makes [`super::dispatch`] run the baseline version on this thread.
        pub(crate) static FORCE_BASELINE: Cell<bool> = const { Cell::new(false) };
    }

    /// Runs `f` with the baseline instruction set on this thread.
    pub(crate) fn with_baseline<R>(f: impl FnOnce() -> R) -> R {
        FORCE_BASELINE.with(|c| c.set(true));
        let out = f();
        FORCE_BASELINE.with(|c| c.set(false));
        out
    }

    #[test]
    fn the_override_and_the_name_agree() {
        assert_eq!(with_baseline(super::kernel_instruction_set), "baseline");
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("FATHOM_SIMD").is_none()
        {
            assert_eq!(super::kernel_instruction_set(), "avx2");
        }
    }
}
