//! The eight-lane kernels in x86 intrinsics, AVX2 and AVX-512F: each the same operations in
//! the same order as the plain Rust it stands for (`portable`, `lerp_lanes`), so the same bits.
//! Every `unsafe` block states what makes it sound.

use super::{LANES, LaneLines, LaneScratch};
use std::arch::x86_64::*;

/// # Safety
/// The processor must have AVX2; `imp` and the scratch must hold at least `out.len() ≥ 2`
/// samples, and `out.len() · LANES` must fit an i32.
#[target_feature(enable = "avx2")]
pub unsafe fn mappings(imp: &[[f32; LANES]], scratch: &mut LaneScratch, out: &mut [[f64; LANES]]) {
    let n = out.len();
    debug_assert!(n >= 2 && imp.len() >= n && scratch.u.len() >= n);
    debug_assert!(scratch.start.len() >= n && n * LANES < i32::MAX as usize);
    let u = scratch.u.as_mut_ptr().cast::<f64>();
    let start = scratch.start.as_mut_ptr().cast::<i32>();
    let imp = imp.as_ptr().cast::<f32>();
    let out = out.as_mut_ptr().cast::<f64>();
    let (zero, one, half) = (
        _mm256_setzero_pd(),
        _mm256_set1_pd(1.0),
        _mm256_set1_pd(0.5),
    );
    let last = (n - 1) as f64;
    // SAFETY (all pointer arithmetic below): sample i of lane l is element i·LANES + l, and
    // i < n, the length of every buffer.
    unsafe {
        // Running sums, both halves at once.
        let mut acc = [zero; 2];
        let mut prev = [weight(imp), weight(imp.add(4))];
        _mm256_storeu_pd(u, zero);
        _mm256_storeu_pd(u.add(4), zero);
        for i in 1..n {
            for h in 0..2 {
                let next = weight(imp.add(i * LANES + 4 * h));
                let w = _mm256_mul_pd(half, _mm256_add_pd(prev[h], next));
                acc[h] = _mm256_add_pd(acc[h], w);
                _mm256_storeu_pd(u.add(i * LANES + 4 * h), acc[h]);
                prev[h] = next;
            }
        }
        let last_v = _mm256_set1_pd(last);
        let to_output = acc.map(|t| _mm256_div_pd(last_v, t));
        let step = acc.map(|t| _mm256_div_pd(t, last_v));
        // Each segment's first output; later (larger) segments overwrite earlier ones.
        std::ptr::write_bytes(start, 0, n * LANES);
        let last_i = _mm_set1_epi32(n as i32 - 1);
        for i in 1..n - 1 {
            for (h, &to_output) in to_output.iter().enumerate() {
                let ui = _mm256_loadu_pd(u.add(i * LANES + 4 * h));
                // min's second operand wins over NaN, as f64::min's non-NaN one does.
                let x = _mm256_min_pd(_mm256_mul_pd(ui, to_output), last_v);
                let up = _mm256_round_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(x);
                let first = _mm_min_epi32(_mm256_cvttpd_epi32(up), last_i);
                let mut f = [0i32; 4];
                _mm_storeu_si128(f.as_mut_ptr().cast(), first);
                for (l, &fl) in f.iter().enumerate() {
                    *start.add(fl as usize * LANES + 4 * h + l) = i as i32;
                }
            }
        }
        // Each output's segment (the running maximum of the starts) and place in it.
        let mut seg = [_mm_setzero_si128(); 2];
        let last_seg = _mm_set1_epi32(n as i32 - 2);
        let lane = [_mm_setr_epi32(0, 1, 2, 3), _mm_setr_epi32(4, 5, 6, 7)];
        for j in 0..n {
            let jf = _mm256_set1_pd(j as f64);
            for h in 0..2 {
                let st = _mm_loadu_si128(start.add(j * LANES + 4 * h).cast());
                seg[h] = _mm_max_epi32(seg[h], st);
                let i = _mm_min_epi32(seg[h], last_seg);
                let at = _mm_add_epi32(_mm_slli_epi32::<3>(i), lane[h]);
                let u0 = _mm256_i32gather_pd::<8>(u, at);
                let u1 = _mm256_i32gather_pd::<8>(u.add(LANES), at);
                let width = _mm256_sub_pd(u1, u0);
                let f = _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(jf, step[h]), u0), width);
                let f = _mm256_and_pd(f, _mm256_cmp_pd::<_CMP_GT_OQ>(width, zero));
                // clamp(0, 1): f is finite here; max gives +0 for −0, which adds the same.
                let f = _mm256_max_pd(_mm256_min_pd(f, one), zero);
                let o = _mm256_add_pd(_mm256_cvtepi32_pd(i), f);
                _mm256_storeu_pd(out.add(j * LANES + 4 * h), o);
            }
        }
    }
}

/// [`mappings`] with AVX-512F: the eight lanes in one register. The same operations in the
/// same order, so the same bits.
///
/// No gathers: each segment's scatter stores its two ends `(u_i, u_{i+1})`, side by side,
/// beside its index, and the output loop carries them forward in registers, taking the new
/// pair in the lanes where a later segment starts (the running maximum's lanes that grow).
/// Each output then loads two registers of pairs and parts them, where [`mappings`] gathers
/// `u` twice. Rejected: the ends scattered with `vscatterdpd` (scatters are slow on AMD EPYC),
/// and each end as a scalar store of its own (a pair is one 128-bit store; docs/decisions.md,
/// “Warp in lanes of eight”); each lane's byte offsets worked out in the register, a third
/// fewer instructions in the scatter and no faster; the next group's running sums made inside
/// this group's output loop, to overlap their chain of additions with the divisions, slower; a
/// copy for lines of 128, no faster (docs/decisions.md, “The CPU stage under 100 µs”).
///
/// # Safety
/// As [`mappings`], with AVX-512F as well.
#[target_feature(enable = "avx512f,avx2")]
pub unsafe fn mappings_avx512(
    imp: &[[f32; LANES]],
    scratch: &mut LaneScratch,
    out: &mut [[f64; LANES]],
) {
    let n = out.len();
    debug_assert!(n >= 2 && imp.len() >= n && scratch.u.len() >= n);
    debug_assert!(scratch.start.len() >= n && n * LANES < i32::MAX as usize);
    debug_assert!(scratch.ends_u.len() >= n);
    let u = scratch.u.as_mut_ptr().cast::<f64>();
    let start = scratch.start.as_mut_ptr().cast::<i32>();
    let imp = imp.as_ptr().cast::<f32>();
    let out = out.as_mut_ptr().cast::<f64>();
    let (zero, one, half) = (
        _mm512_setzero_pd(),
        _mm512_set1_pd(1.0),
        _mm512_set1_pd(0.5),
    );
    let last = (n - 1) as f64;
    // SAFETY (all pointer arithmetic below): sample i of lane l is element i·LANES + l, and
    // i < n, the length of every buffer; in `ends_u` its pair is f64s 2(i·LANES + l) and one
    // more, below the 2·n·LANES there.
    unsafe {
        let weight = |p: *const f32| {
            let v = _mm512_cvtps_pd(_mm256_loadu_ps(p));
            let ok = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(v, zero)
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(v, _mm512_set1_pd(f64::INFINITY));
            _mm512_maskz_mov_pd(ok, v)
        };
        let mut acc = zero;
        let mut prev = weight(imp);
        _mm512_storeu_pd(u, zero);
        for i in 1..n {
            let next = weight(imp.add(i * LANES));
            acc = _mm512_add_pd(acc, _mm512_mul_pd(half, _mm512_add_pd(prev, next)));
            _mm512_storeu_pd(u.add(i * LANES), acc);
            prev = next;
        }
        let last_v = _mm512_set1_pd(last);
        let to_output = _mm512_div_pd(last_v, acc);
        let step = _mm512_div_pd(acc, last_v);
        std::ptr::write_bytes(start, 0, n * LANES);
        let last_i = _mm256_set1_epi32(n as i32 - 1);
        let ends_u = scratch.ends_u.as_mut_ptr().cast::<f64>();
        let mut ui = _mm512_loadu_pd(u.add(LANES));
        for i in 1..n - 1 {
            let next = _mm512_loadu_pd(u.add((i + 1) * LANES));
            let x = _mm512_min_pd(_mm512_mul_pd(ui, to_output), last_v);
            let up = _mm512_roundscale_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(x);
            let first = _mm256_min_epi32(_mm512_cvttpd_epi32(up), last_i);
            let mut f = [0i32; LANES];
            _mm256_storeu_si256(f.as_mut_ptr().cast(), first);
            // Lane l's pair (u_i, u_{i+1}) is the 128-bit block l/2 of `even` (l even) or
            // `odd`.
            let even = _mm512_castpd_ps(_mm512_unpacklo_pd(ui, next));
            let odd = _mm512_castpd_ps(_mm512_unpackhi_pd(ui, next));
            let at = |l: usize| f[l] as usize * LANES + l;
            for l in 0..LANES {
                *start.add(at(l)) = i as i32;
            }
            let put = |l: usize, v: __m128| _mm_storeu_ps(ends_u.add(2 * at(l)).cast(), v);
            put(0, _mm512_extractf32x4_ps::<0>(even));
            put(1, _mm512_extractf32x4_ps::<0>(odd));
            put(2, _mm512_extractf32x4_ps::<1>(even));
            put(3, _mm512_extractf32x4_ps::<1>(odd));
            put(4, _mm512_extractf32x4_ps::<2>(even));
            put(5, _mm512_extractf32x4_ps::<2>(odd));
            put(6, _mm512_extractf32x4_ps::<3>(even));
            put(7, _mm512_extractf32x4_ps::<3>(odd));
            ui = next;
        }
        let mut seg = _mm512_setzero_si512();
        let last_seg = _mm256_set1_epi32(n as i32 - 2);
        // Segment 0's ends, until a later segment starts. A lane takes a stored pair only
        // where its segment grows, so pairs left over from earlier lines are masked off.
        let mut u0 = zero;
        let mut u1 = _mm512_loadu_pd(u.add(LANES));
        let (lower, upper) = (
            _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14),
            _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15),
        );
        for j in 0..n {
            let jf = _mm512_set1_pd(j as f64);
            let st = _mm512_zextsi256_si512(_mm256_loadu_si256(start.add(j * LANES).cast()));
            let new = _mm512_cmpgt_epi32_mask(st, seg) as __mmask8;
            seg = _mm512_max_epi32(seg, st);
            let a = _mm512_loadu_pd(ends_u.add(j * 2 * LANES));
            let b = _mm512_loadu_pd(ends_u.add(j * 2 * LANES + LANES));
            u0 = _mm512_mask_mov_pd(u0, new, _mm512_permutex2var_pd(a, lower, b));
            u1 = _mm512_mask_mov_pd(u1, new, _mm512_permutex2var_pd(a, upper, b));
            let i = _mm256_min_epi32(_mm512_castsi512_si256(seg), last_seg);
            let width = _mm512_sub_pd(u1, u0);
            let f = _mm512_div_pd(_mm512_sub_pd(_mm512_mul_pd(jf, step), u0), width);
            let f = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask::<_CMP_GT_OQ>(width, zero), f);
            let f = _mm512_max_pd(_mm512_min_pd(f, one), zero);
            let o = _mm512_add_pd(_mm512_cvtepi32_pd(i), f);
            _mm512_storeu_pd(out.add(j * LANES), o);
        }
    }
}

/// [`super::lerp_lanes`]: the same operations, gathered. `a` is clamped to [0, n − 2] before
/// it becomes an index, which is what `lerp_at`'s saturating cast and min give (NaN: 0).
///
/// # Safety
/// The processor must have AVX2; `lines` was made for `values` (so each lane's line lies
/// whole in it), which holds fewer than 2^31 samples.
#[target_feature(enable = "avx2")]
pub unsafe fn lerp(values: &[f32], lines: &LaneLines, a: &[f64; LANES]) -> [f32; LANES] {
    // SAFETY: every index is a line's start plus at most n − 2, and then one more.
    unsafe {
        let (at, f) = lerp_index(lines, a);
        let v0 = _mm256_i32gather_ps::<4>(values.as_ptr(), at);
        let v1 = _mm256_i32gather_ps::<4>(values.as_ptr().add(1), at);
        finish_lerp(v0, v1, f)
    }
}

/// [`lerp`] with AVX-512F: each lane's two samples, side by side in memory, gathered as one
/// 64-bit element and then parted, so one gather of eight elements instead of two.
///
/// # Safety
/// As [`lerp`], with AVX-512F as well.
#[target_feature(enable = "avx512f,avx2")]
pub unsafe fn lerp_avx512(values: &[f32], lines: &LaneLines, a: &[f64; LANES]) -> [f32; LANES] {
    // SAFETY: every pair starts at a line's start plus at most n − 2, so it ends inside the
    // line; the gather's scale of 4 counts offsets in f32s.
    unsafe {
        let (at, f) = lerp_index(lines, a);
        let pairs = _mm512_castpd_ps(_mm512_i32gather_pd::<4>(at, values.as_ptr().cast()));
        let parted = _mm512_permutexvar_ps(
            _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15),
            pairs,
        );
        let v0 = _mm512_castps512_ps256(parted);
        let v1 = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(parted)));
        finish_lerp(v0, v1, f)
    }
}

/// Each lane's index into `values` (its line's start plus the segment) and weight, for
/// [`lerp`] and [`lerp_avx512`].
#[inline]
#[target_feature(enable = "avx2")]
fn lerp_index(lines: &LaneLines, a: &[f64; LANES]) -> (__m256i, __m256) {
    let n = lines.n;
    // SAFETY: both arrays hold eight lanes.
    let (base, a0, a1) = unsafe {
        (
            _mm256_loadu_si256(lines.start32.as_ptr().cast()),
            _mm256_loadu_pd(a.as_ptr()),
            _mm256_loadu_pd(a.as_ptr().add(4)),
        )
    };
    // min's second operand wins over NaN, and max's: NaN becomes 0, as `as usize` has it.
    let (top, zero) = (_mm256_set1_pd((n - 2) as f64), _mm256_setzero_pd());
    let clamp = |a| _mm256_max_pd(_mm256_min_pd(top, a), zero);
    let (i0, i1) = (
        _mm256_cvttpd_epi32(clamp(a0)),
        _mm256_cvttpd_epi32(clamp(a1)),
    );
    let i = _mm256_set_m128i(i1, i0);
    let f0 = _mm256_cvtpd_ps(_mm256_sub_pd(
        a0,
        _mm256_cvtepi32_pd(_mm256_castsi256_si128(i)),
    ));
    let f1 = _mm256_cvtpd_ps(_mm256_sub_pd(
        a1,
        _mm256_cvtepi32_pd(_mm256_extracti128_si256::<1>(i)),
    ));
    (_mm256_add_epi32(base, i), _mm256_set_m128(f1, f0))
}

/// `v0 + (v1 − v0)·f`, lane by lane, as `lerp_at` computes it.
#[inline]
#[target_feature(enable = "avx2")]
fn finish_lerp(v0: __m256, v1: __m256, f: __m256) -> [f32; LANES] {
    let v = _mm256_add_ps(v0, _mm256_mul_ps(_mm256_sub_ps(v1, v0), f));
    let mut out = [0.0f32; LANES];
    // SAFETY: `out` holds eight lanes.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) };
    out
}

/// Four lanes' weights: the importance where it is finite and positive, else 0.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn weight(p: *const f32) -> __m256d {
    // SAFETY: the caller's pointer holds four samples.
    let v = _mm256_cvtps_pd(unsafe { _mm_loadu_ps(p) });
    let inf = _mm256_set1_pd(f64::INFINITY);
    let zero = _mm256_setzero_pd();
    let ok = _mm256_and_pd(
        _mm256_cmp_pd::<_CMP_GT_OQ>(v, zero),
        _mm256_cmp_pd::<_CMP_LT_OQ>(v, inf),
    );
    _mm256_and_pd(v, ok)
}

/// Lane l's value of its line at `a[l]` and the weights of [`lerp_avx512`], with `a` in a
/// register: [`lerp_index`]'s clamp, conversions and offsets on all eight lanes at once.
#[inline]
#[target_feature(enable = "avx512f,avx2")]
unsafe fn lerp_wide(values: *const f32, base: __m256i, top: __m512d, a: __m512d) -> __m256 {
    // min's second operand wins over NaN, and max's: NaN becomes 0, as `as usize` has it.
    let i = _mm512_cvttpd_epi32(_mm512_max_pd(_mm512_min_pd(top, a), _mm512_setzero_pd()));
    let f = _mm512_cvtpd_ps(_mm512_sub_pd(a, _mm512_cvtepi32_pd(i)));
    // SAFETY: the caller's lines hold every index, each a line's start plus at most n − 2, and
    // its pair ends inside the line.
    let pairs = unsafe {
        _mm512_castpd_ps(_mm512_i32gather_pd::<4>(
            _mm256_add_epi32(base, i),
            values.cast(),
        ))
    };
    let parted = _mm512_permutexvar_ps(
        _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15),
        pairs,
    );
    let v0 = _mm512_castps512_ps256(parted);
    let v1 = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(parted)));
    _mm256_add_ps(v0, _mm256_mul_ps(_mm256_sub_ps(v1, v0), f))
}

/// The row pass's loop over a group of eight whole lines in one kernel (`super::row_samples`):
/// for each output s, `(a·d0) as f32` to `x[s·n + first ..]` and [`lerp_avx512`]'s value to
/// `v[s·n + first ..]`, a = `maps[s]`.
///
/// # Safety
/// The processor must have AVX-512F and AVX2; `lines` was made for `values` (fewer than 2^31
/// samples); `x` and `v` hold `maps.len()` lines of `lines.n` samples and
/// `first + LANES ≤ lines.n`.
#[target_feature(enable = "avx512f,avx2")]
pub unsafe fn row_samples(
    values: &[f32],
    lines: &LaneLines,
    maps: &[[f64; LANES]],
    d0: f64,
    x: &mut [f32],
    v: &mut [f32],
    first: usize,
) {
    let n = lines.n;
    // SAFETY: `start32` holds eight lanes; map s and the stores' eight samples at
    // s·n + first + l, l < LANES, lie inside their buffers (the caller's bounds).
    unsafe {
        let base = _mm256_loadu_si256(lines.start32.as_ptr().cast());
        let top = _mm512_set1_pd((n - 2) as f64);
        let d0 = _mm512_set1_pd(d0);
        let (xp, vp) = (x.as_mut_ptr().add(first), v.as_mut_ptr().add(first));
        for (s, a) in maps.iter().enumerate() {
            let a = _mm512_loadu_pd(a.as_ptr());
            _mm256_storeu_ps(xp.add(s * n), _mm512_cvtpd_ps(_mm512_mul_pd(a, d0)));
            _mm256_storeu_ps(vp.add(s * n), lerp_wide(values.as_ptr(), base, top, a));
        }
    }
}

/// The column pass's loop over a group of eight whole columns in one kernel
/// (`super::column_points`): for each output t, point `s0 + l` of Φ's row t is lane l's
/// [`lerp_avx512`] of `row_x` at b and `(b·d0) as f32`, b = `maps[t]`.
///
/// # Safety
/// The processor must have AVX-512F and AVX2; `lines` was made for `row_x` (fewer than 2^31
/// samples); `phi` holds `maps.len()` rows of `lines.n` points and `s0 + LANES ≤ lines.n`.
#[target_feature(enable = "avx512f,avx2")]
pub unsafe fn column_points(
    row_x: &[f32],
    lines: &LaneLines,
    maps: &[[f64; LANES]],
    d0: f64,
    phi: &mut [[f32; 2]],
    s0: usize,
) {
    let n = lines.n;
    // SAFETY: `start32` holds eight lanes; map t and the eight points at t·n + s0 + l, l < LANES,
    // lie inside their buffers (the caller's bounds).
    unsafe {
        let base = _mm256_loadu_si256(lines.start32.as_ptr().cast());
        let top = _mm512_set1_pd((n - 2) as f64);
        let d0 = _mm512_set1_pd(d0);
        // x and y of each lane side by side.
        let zip = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
        let out = phi.as_mut_ptr().add(s0).cast::<f32>();
        for (t, b) in maps.iter().enumerate() {
            let b = _mm512_loadu_pd(b.as_ptr());
            let x = lerp_wide(row_x.as_ptr(), base, top, b);
            let y = _mm512_cvtpd_ps(_mm512_mul_pd(b, d0));
            let p =
                _mm512_permutex2var_ps(_mm512_castps256_ps512(x), zip, _mm512_castps256_ps512(y));
            _mm512_storeu_ps(out.add(2 * t * n), p);
        }
    }
}
