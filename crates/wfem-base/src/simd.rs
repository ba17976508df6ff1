//! [`clear_upper_state`]: scalar code after wide SIMD kernels at full speed.
//!
//! faer's matrix products run AVX-512 microkernels (the `gemm` crate's `simd512`) on the
//! calling thread and on rayon's workers, and leave the upper halves of the vector registers
//! dirty. Every later scalar SSE instruction on that thread — ours, and libm's `exp`/`log` —
//! then pays a transition penalty: describing a 15,000-vertex shape spent 1.1 of its 2.2 s in
//! `exp` of the word weights (146 ns per call instead of ~5). One `vzeroupper` at the start of
//! a scalar-heavy task ends that: the same description takes 1.24 s.

/// Clears the upper state of the vector registers (`vzeroupper`) on x86-64 with AVX; nothing
/// elsewhere. Cheap (one instruction): call it at the start of every parallel task or loop
/// that does scalar floating-point work (exp, log, distances) after matrix products.
#[inline]
pub fn clear_upper_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // `unsafe fn` (not a safe target-feature fn) builds with the workspace's Rust 1.85.
            #[target_feature(enable = "avx")]
            #[allow(unsafe_code)]
            unsafe fn zero_upper() {
                #[allow(unused_unsafe)]
                unsafe {
                    std::arch::x86_64::_mm256_zeroupper()
                }
            }
            // SAFETY: the CPU has AVX (checked just above), all that `zero_upper` needs.
            #[allow(unsafe_code)]
            unsafe {
                zero_upper()
            }
        }
    }
}

/// Asks the CPU to bring the memory of `items` (its first 512 bytes) into the caches (x86-64
/// `prefetcht1`: the second-level cache and inward); nothing elsewhere. A hint: it changes no
/// value, and it pays when the data is read some hundreds of cycles later, as fast marching
/// reads a vertex's triangles when it accepts the vertex, long after it first reached it.
#[inline]
pub fn prefetch<T>(items: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        let start = items.as_ptr().cast::<i8>();
        let bytes = std::mem::size_of_val(items).min(512);
        let mut offset = 0;
        while offset < bytes {
            // SAFETY: a prefetch never faults and reads nothing into the program; the address
            // is inside the slice. SSE (which has the instruction) is part of x86-64.
            #[allow(unsafe_code, unused_unsafe)]
            unsafe {
                std::arch::x86_64::_mm_prefetch(start.add(offset), std::arch::x86_64::_MM_HINT_T1);
            }
            offset += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = items;
}

#[cfg(test)]
mod tests {
    #[test]
    fn clearing_keeps_values() {
        // Runs where it must (an AVX machine executes the instruction) and changes no scalar
        // result computed across it.
        let x: Vec<f64> = (0..64).map(|i| (i as f64 * 0.37).sin()).collect();
        let before: f64 = x.iter().map(|v| v.exp()).sum();
        super::clear_upper_state();
        let after: f64 = x.iter().map(|v| v.exp()).sum();
        assert_eq!(before, after);
    }
}
