//! Running a kernel at the machine's vector width (issue #8). The crate is compiled for the
//! baseline x86-64 (SSE2: two doubles per instruction) so that a wheel runs everywhere; the lab
//! kernels are written as plain loops over fixed-size lane blocks, and [`wide_fn!`] compiles each
//! entry point twice, once with AVX2 (four doubles per instruction, and `round`/`floor` as single
//! instructions), chosen once at run time by the CPU. Only the instruction set changes: no fused
//! multiply-add, so both versions compute the same bits.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by tests to run the baseline versions on an AVX2 machine.
static BASELINE_ONLY: AtomicBool = AtomicBool::new(false);

/// Run the baseline versions even where AVX2 is available (`true`), or choose by the CPU again.
#[cfg(test)]
pub(crate) fn force_baseline(on: bool) {
    BASELINE_ONLY.store(on, Ordering::SeqCst);
}

/// Whether this CPU runs the AVX2 versions (checked once, then cached by `std`).
#[inline(always)]
pub fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        !BASELINE_ONLY.load(Ordering::Relaxed) && std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// `fn name(args) -> ret { body }` defined so that `body` (with everything it calls inlined:
/// mark the kernels `#[inline(always)]`) is compiled both for the baseline and with AVX2, and
/// the AVX2 version runs when the CPU has it.
macro_rules! wide_fn {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident : $ty:ty),* $(,)?) -> $ret:ty $body:block) => {
        $(#[$meta])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn inner($($arg: $ty),*) -> $ret $body
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            #[allow(clippy::too_many_arguments)]
            unsafe fn avx2($($arg: $ty),*) -> $ret {
                inner($($arg),*)
            }
            #[cfg(target_arch = "x86_64")]
            {
                if $crate::lab::wide::has_avx2() {
                    // SAFETY: the CPU supports AVX2 (checked just above).
                    return unsafe { avx2($($arg),*) };
                }
            }
            inner($($arg),*)
        }
    };
}
pub(crate) use wide_fn;
