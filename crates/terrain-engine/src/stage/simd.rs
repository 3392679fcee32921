//! Which of the stage's builds the processor can run: the loops and kernels built for AVX-512F
//! (which use AVX2's 256-bit integer operations beside it) and those built for AVX2, chosen at
//! run time. The checks are cached by the standard library, so a call per row costs a load.
//!
//! Rule: a build is taken only where the processor reports every feature it is compiled with;
//! a virtual machine may report AVX-512F without AVX2.

/// Whether the AVX-512 builds can run: AVX-512F and AVX2 both.
#[inline]
pub fn avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether the AVX2 builds can run.
#[inline]
pub fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
