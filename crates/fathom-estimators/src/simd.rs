//! Run-time choice of the vector instruction set for the fixed-size Kalman kernels.
//!
//! The crate is built for the default `x86-64` target (SSE2). `dispatch` runs a
//! closure compiled a second time with AVX2 enabled (through `pulp`, which `faer`
//! already uses) when the CPU has it, so the `#[inline(always)]` kernels of
//! `linalg` inlined into the closure use 4-wide vectors (measured: the 6-state /
//! 3-measurement step ~10 % faster, the 9 / 3 step ~15 %). Rust never fuses a
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

/// The instruction set found at first use (one atomic load afterwards).
fn arch() -> pulp::Arch {
    static ARCH: OnceLock<pulp::Arch> = OnceLock::new();
    #[cfg(test)]
    if tests::FORCE_BASELINE.with(std::cell::Cell::get) {
        return pulp::Arch::Scalar;
    }
    *ARCH.get_or_init(|| {
        if std::env::var_os("FATHOM_SIMD").is_some_and(|v| v == "baseline") {
            pulp::Arch::Scalar
        } else {
            pulp::Arch::new()
        }
    })
}

/// Runs `f` compiled for the widest instruction set this CPU has. Only what is
/// inlined into `f` benefits: the kernels are `#[inline(always)]`, and so must be the
/// closure (`#[inline(always)] || ...`), or it stays a baseline function.
#[inline(always)]
pub(crate) fn dispatch<R>(f: impl FnOnce() -> R) -> R {
    arch().dispatch(f)
}

/// The instruction set the Kalman kernels run with on this machine: `"avx2"` or
/// `"baseline"` (SSE2 on x86-64; the only one on other architectures).
pub fn kernel_instruction_set() -> &'static str {
    match arch() {
        pulp::Arch::Scalar => "baseline",
        _ => "avx2",
    }
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
