//! Transposing an n² map, for the warp that runs across (`stage::warp`, `Warp::run_across`): the
//! importance before it, and Φ after it, each point's x and y swapped.
//!
//! Rules: out of place; blocks of 8 × 8 importance texels and 4 × 4 points transposed in AVX2
//! registers where the processor has it, written out row by row of the output, so that each
//! output row is filled in order; the rows and columns past the last whole block, and a
//! processor without AVX2, one value at a time. Every build gives the same values (a transpose
//! only moves them; tested). Φ's 4 × 4 blocks go two side by side, so that each input line is read
//! whole.
//!
//! Rejected (docs/decisions.md, “Transposition in blocks”): one value at a time in tiles, several
//! times slower; blocks walked by input rows, no faster than that, as the output's rows (512 bytes
//! apart at 128²) fall into a few of L1's sets and each block's half-filled lines are evicted
//! before the next fills them; blocks as plain Rust arrays for the compiler to vectorise.

/// `dst[i·n + j] = src[j·n + i]` for an n² map.
pub fn importance(src: &[f32], dst: &mut [f32], n: usize) {
    assert!(src.len() == n * n && dst.len() == n * n, "maps of {n}²");
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx2() {
        // SAFETY: the processor has AVX2, checked just above; both maps hold n² values.
        return unsafe { x86::importance(src, dst, n) };
    }
    rest(src, dst, n, 0, |v| v);
}

/// `dst[i·n + j] = src[j·n + i]` with x and y swapped: Φ of the map transposed, back in the
/// map's own frame.
pub fn phi(src: &[[f32; 2]], dst: &mut [[f32; 2]], n: usize) {
    assert!(src.len() == n * n && dst.len() == n * n, "maps of {n}²");
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx2() {
        // SAFETY: as above.
        return unsafe { x86::phi(src, dst, n) };
    }
    rest(src, dst, n, 0, |[x, y]| [y, x]);
}

/// The values the blocks (the first `whole` rows and columns) leave: all of them for `whole` 0.
#[inline(always)]
fn rest<T: Copy>(src: &[T], dst: &mut [T], n: usize, whole: usize, f: impl Fn(T) -> T) {
    for j in 0..n {
        let from = if j < whole { whole } else { 0 };
        for i in from..n {
            dst[i * n + j] = f(src[j * n + i]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// # Safety
    /// The processor has AVX2, and `src` and `dst` hold n² values each.
    #[target_feature(enable = "avx2")]
    pub unsafe fn importance(src: &[f32], dst: &mut [f32], n: usize) {
        let whole = n / 8 * 8;
        for i0 in (0..whole).step_by(8) {
            for j0 in (0..whole).step_by(8) {
                // SAFETY: rows j0..j0 + 8 and columns i0..i0 + 8 lie in the n² source, rows
                // i0..i0 + 8 and columns j0..j0 + 8 in the n² destination.
                unsafe {
                    block_8x8(
                        src.as_ptr().add(j0 * n + i0),
                        dst.as_mut_ptr().add(i0 * n + j0),
                        n,
                    )
                }
            }
        }
        super::rest(src, dst, n, whole, |v| v);
    }

    /// # Safety
    /// As [`importance`]: AVX2, and n² points in each map.
    #[target_feature(enable = "avx2")]
    pub unsafe fn phi(src: &[[f32; 2]], dst: &mut [[f32; 2]], n: usize) {
        let whole = n / 8 * 8;
        for i0 in (0..whole).step_by(8) {
            for j0 in (0..whole).step_by(4) {
                for i in [i0, i0 + 4] {
                    // SAFETY: as in `importance`, for 4 × 4 points.
                    unsafe {
                        points_4x4(
                            src.as_ptr().add(j0 * n + i),
                            dst.as_mut_ptr().add(i * n + j0),
                            n,
                        )
                    }
                }
            }
        }
        super::rest(src, dst, n, whole, |[x, y]| [y, x]);
    }

    /// The 8 × 8 block at `src` (rows n apart) transposed to `dst` (rows n apart).
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn block_8x8(src: *const f32, dst: *mut f32, n: usize) {
        // SAFETY: the caller's: eight rows of eight f32 at each pointer.
        unsafe {
            let r: [__m256; 8] = std::array::from_fn(|k| _mm256_loadu_ps(src.add(k * n)));
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpackhi_ps(r[0], r[1]);
            let t2 = _mm256_unpacklo_ps(r[2], r[3]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            let t4 = _mm256_unpacklo_ps(r[4], r[5]);
            let t5 = _mm256_unpackhi_ps(r[4], r[5]);
            let t6 = _mm256_unpacklo_ps(r[6], r[7]);
            let t7 = _mm256_unpackhi_ps(r[6], r[7]);
            let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
            let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
            let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
            let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
            let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
            let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
            let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
            let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
            let out = [
                _mm256_permute2f128_ps::<0x20>(u0, u4),
                _mm256_permute2f128_ps::<0x20>(u1, u5),
                _mm256_permute2f128_ps::<0x20>(u2, u6),
                _mm256_permute2f128_ps::<0x20>(u3, u7),
                _mm256_permute2f128_ps::<0x31>(u0, u4),
                _mm256_permute2f128_ps::<0x31>(u1, u5),
                _mm256_permute2f128_ps::<0x31>(u2, u6),
                _mm256_permute2f128_ps::<0x31>(u3, u7),
            ];
            for (k, v) in out.into_iter().enumerate() {
                _mm256_storeu_ps(dst.add(k * n), v);
            }
        }
    }

    /// The 4 × 4 block of points at `src` transposed to `dst`, each point's x and y swapped.
    #[inline]
    #[target_feature(enable = "avx2")]
    unsafe fn points_4x4(src: *const [f32; 2], dst: *mut [f32; 2], n: usize) {
        // SAFETY: the caller's: four rows of four points at each pointer; a point is two f32,
        // read and written as one f64's bits.
        unsafe {
            let r: [__m256d; 4] = std::array::from_fn(|k| _mm256_loadu_pd(src.add(k * n).cast()));
            let t0 = _mm256_unpacklo_pd(r[0], r[1]);
            let t1 = _mm256_unpackhi_pd(r[0], r[1]);
            let t2 = _mm256_unpacklo_pd(r[2], r[3]);
            let t3 = _mm256_unpackhi_pd(r[2], r[3]);
            let out = [
                _mm256_permute2f128_pd::<0x20>(t0, t2),
                _mm256_permute2f128_pd::<0x20>(t1, t3),
                _mm256_permute2f128_pd::<0x31>(t0, t2),
                _mm256_permute2f128_pd::<0x31>(t1, t3),
            ];
            for (k, v) in out.into_iter().enumerate() {
                let swapped = _mm256_permute_ps::<0b10_11_00_01>(_mm256_castpd_ps(v));
                _mm256_storeu_ps(dst.add(k * n).cast(), swapped);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every side, whole blocks or not, and every build (AVX2 where the processor has it, the
    /// plain loop) moves each value to its place.
    #[test]
    fn every_build_transposes_every_side() {
        for n in [1, 2, 3, 7, 8, 9, 12, 16, 37, 128] {
            let src: Vec<f32> = (0..n * n).map(|k| k as f32 + 0.5).collect();
            let points: Vec<[f32; 2]> = (0..n * n).map(|k| [k as f32, -(k as f32) - 1.0]).collect();
            let (mut a, mut p) = (vec![0.0; n * n], vec![[0.0; 2]; n * n]);
            importance(&src, &mut a, n);
            phi(&points, &mut p, n);
            let (mut b, mut q) = (vec![0.0; n * n], vec![[0.0; 2]; n * n]);
            rest(&src, &mut b, n, 0, |v| v);
            rest(&points, &mut q, n, 0, |[x, y]| [y, x]);
            for j in 0..n {
                for i in 0..n {
                    assert_eq!(a[i * n + j], src[j * n + i], "n = {n}, ({i}, {j})");
                    let [x, y] = points[j * n + i];
                    assert_eq!(p[i * n + j], [y, x], "n = {n}, ({i}, {j})");
                }
            }
            assert_eq!((a, p), (b, q), "n = {n}");
        }
    }
}
