//! Resampling the atlas on a sketch map's lattice: trilinear between two mip levels, separable
//! taps along x and y, an axis-aligned region row by row and a turned one in runs along the finer
//! lattice's rows. One body built for AVX-512 and the baseline, chosen at run time; the AVX-512
//! taps (`x86::taps`) give the scalar loop's bits.

use super::Turn;
use crate::sketch::Atlas;
use crate::stage::lines::LANES;
use glam::DVec2;

/// Bilinear taps of one level along one axis: for each output sample, the lower texel and the
/// weight of the upper one. Sampling a lattice is separable, so a frame computes 2·n taps per level
/// instead of a division and a floor per sample.
#[derive(Clone, Debug, Default)]
pub struct Taps {
    index: Vec<u32>,
    frac: Vec<f32>,
}

impl Taps {
    /// Tap k: the lower texel and the weight of the upper one.
    #[inline(always)]
    fn at(&self, k: usize) -> (usize, f32) {
        (self.index[k] as usize, self.frac[k])
    }

    /// Taps at level-0 texel coordinates `c0 + k·dc`, k < n, on a level `size` texels long that is
    /// level `l` of the pyramid.
    #[inline(always)]
    fn fill(&mut self, c0: f64, dc: f64, n: usize, l: usize, size: usize) {
        let s = (1u64 << l) as f64;
        // s is a power of two, so a product by its inverse is the division, bit for bit.
        let inv_s = 1.0 / s;
        let off = (s - 1.0) * 0.5;
        self.index.resize(n, 0);
        self.frac.resize(n, 0.0);
        let hi = (size - 1) as f64;
        for k in 0..n {
            let c = ((c0 + k as f64 * dc - off) * inv_s).clamp(0.0, hi);
            let i = (c as usize).min(size - 2); // c ≥ 0: the cast is floor
            self.index[k] = i as u32;
            self.frac[k] = (c - i as f64) as f32;
        }
    }
}

/// Scratch for [`resample`]: taps for x and y at the two levels sampled,
/// and one level row interpolated between two source rows (`vertical`).
#[derive(Clone, Debug, Default)]
pub struct Resampler {
    x: [Taps; 2],
    y: [Taps; 2],
    vertical: Vec<f32>,
    /// A turned region's taps along x: every other lattice column, from the first or the second
    /// (`resample_runs`), at each level.
    runs: [[Taps; 2]; 2],
    /// A turned region's samples, lattice row by lattice row (`resample_runs`).
    skewed: Vec<f32>,
}

/// Samples `atlas` on the n² lattice `origin + (i, j)·spacing`, trilinear between the two mip
/// levels around the lattice's spacing.
///
/// Each output row first interpolates the two source rows under it over the span of texels its
/// taps touch (a contiguous loop), then takes the taps along x from that; taking all four texels
/// per output sample costs more than twice as much. The row scratch grows to its span once. With
/// AVX-512F the taps along x are gathered, each output's two texels as one 64-bit element, or
/// taken by permutes from a window (`x86::taps`). Rejected: gathering them eight at a time with
/// AVX2, each texel apart (no faster; docs/decisions.md, “Sketch map resampling”).
///
/// Built for AVX-512 where the processor has it (`resample_avx512`), so that the rows' vertical
/// interpolation runs sixteen lanes wide. The same operations, so the same bits.
///
/// A region turned by `turn` is sampled by `resample_runs`, through the same dispatch.
pub fn resample(
    atlas: &Atlas,
    origin: DVec2,
    spacing: f64,
    turn: Turn,
    n: usize,
    out: &mut [f32],
    r: &mut Resampler,
) {
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() {
        // SAFETY: the processor has AVX-512F and AVX2 (`simd::avx512`), checked just above.
        return unsafe { resample_avx512(atlas, origin, spacing, turn, n, out, r) };
    }
    resample_runs(atlas, origin, spacing, turn, n, out, r);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
unsafe fn resample_avx512(
    atlas: &Atlas,
    origin: DVec2,
    spacing: f64,
    turn: Turn,
    n: usize,
    out: &mut [f32],
    r: &mut Resampler,
) {
    resample_runs(atlas, origin, spacing, turn, n, out, r);
}

#[inline(always)]
fn resample_rows(
    atlas: &Atlas,
    origin: DVec2,
    spacing: f64,
    n: usize,
    out: &mut [f32],
    r: &mut Resampler,
) {
    let (l0, l1, t) = levels(atlas, spacing);
    let u0 = (origin.x - atlas.origin.x) / atlas.dx;
    let v0 = (origin.y - atlas.origin.y) / atlas.dy;
    for (k, l) in [l0, l1].into_iter().enumerate() {
        let level = &atlas.levels[l];
        r.x[k].fill(u0, spacing / atlas.dx, n, l, level.width);
        r.y[k].fill(v0, spacing / atlas.dy, n, l, level.height);
    }
    let blend = t > 0.0 && l1 != l0;
    for j in 0..n {
        let row = &mut out[j * n..(j + 1) * n];
        let Resampler { x, y, vertical, .. } = r;
        let taps = |k: usize| ((&x[k].index[..], &x[k].frac[..]), y[k].at(j));
        let (tx, ty) = taps(0);
        sample_row(&atlas.levels[l0], tx, ty, vertical, row, None);
        if blend {
            let (tx, ty) = taps(1);
            sample_row(&atlas.levels[l1], tx, ty, vertical, row, Some(t));
        }
    }
}

/// [`resample`]'s samples for a region turned by `turn` (an axis-aligned one goes to
/// `resample_rows`), whose texel (i, j) lies at `origin + (i·a + j·b)·d_b`
/// with `d_b = spacing/√2` and a, b its [`Turn::lattice_steps`]: the texels are points of the
/// world lattice of spacing `d_b`, so each lattice row (one y) holds a run of them every other
/// lattice column, one texel further along s each. Each run is sampled as an axis-aligned row is
/// (the vertical interpolation over its span, then the taps along x, at the levels of `spacing`,
/// as [`resample`] takes them), into a row of `r.skewed`, and then the texels are read from them
/// in order, as a slice's stride. A turned map makes twice the calls of an axis-aligned one, each
/// half as long.
///
/// Rejected: each run's samples written straight to their texels (each write to another cache
/// line), and runs started on a 32-byte boundary (the extra samples cost more than the straddled
/// stores; docs/decisions.md, “Sketch map resampling”).
#[inline(always)]
fn resample_runs(
    atlas: &Atlas,
    origin: DVec2,
    spacing: f64,
    turn: Turn,
    n: usize,
    out: &mut [f32],
    r: &mut Resampler,
) {
    let Some((a, b)) = turn.lattice_steps() else {
        return resample_rows(atlas, origin, spacing, n, out, r);
    };
    // Both turns step one lattice row up along t (b[1] = 1), and along s one up or down
    // (a[1] = ∓1); along a lattice row, the next texel is one along s and a[1] along t: two
    // lattice columns on (a[0] − a[1]·b[0] = 2).
    debug_assert!(b[1] == 1 && a[1].abs() == 1 && a[0] - a[1] * b[0] == 2);
    let (l0, l1, t) = levels(atlas, spacing);
    let d_b = spacing * std::f64::consts::FRAC_1_SQRT_2;
    let last = n as i64 - 1;
    // Lattice row y' = j + a[1]·i of texel (i, j), relative to the corner's; column
    // x' = 2i + b[0]·y'.
    let (y_lo, y_hi) = if a[1] < 0 {
        (-last, last)
    } else {
        (0, 2 * last)
    };
    // The least lattice column, x' = i·a[0] + j·b[0], at a corner of the region.
    let x_lo = [0, last]
        .into_iter()
        .flat_map(|i| [0, last].map(|j| i * a[0] + j * b[0]))
        .min()
        .unwrap_or(0);
    // Each parity's lattice columns from x_lo (or one past), every other one; and LANES more,
    // so that every run can take whole groups of eight taps (the rest are sampled, not kept).
    let columns = n + 1 + LANES;
    let u0 = (origin.x - atlas.origin.x) / atlas.dx;
    let v0 = (origin.y - atlas.origin.y) / atlas.dy;
    let rows = (y_hi - y_lo + 1) as usize;
    // Lattice row y' − y_lo's samples at [(y' − y_lo)·w + i], i its texels' first index, with
    // room for a run's last group of eight.
    let w = n + LANES;
    r.skewed.resize(rows * w, 0.0);
    for (k, l) in [l0, l1].into_iter().enumerate() {
        let level = &atlas.levels[l];
        for p in 0..2 {
            let first = u0 + (x_lo + p as i64) as f64 * d_b / atlas.dx;
            r.runs[p][k].fill(first, 2.0 * d_b / atlas.dx, columns, l, level.width);
        }
        r.y[k].fill(
            v0 + y_lo as f64 * d_b / atlas.dy,
            d_b / atlas.dy,
            rows,
            l,
            level.height,
        );
    }
    let blend = t > 0.0 && l1 != l0;
    for y in y_lo..=y_hi {
        // Texels (i, y − a[1]·i) of the region, i in [i_lo, i_hi].
        let (i_lo, i_hi) = if a[1] < 0 {
            ((-y).max(0), last.min(last - y))
        } else {
            ((y - last).max(0), last.min(y))
        };
        if i_lo > i_hi {
            continue;
        }
        let len = ((i_hi - i_lo + 1) as usize).next_multiple_of(LANES);
        let x_first = 2 * i_lo + b[0] * y;
        let p = (x_first - x_lo).rem_euclid(2) as usize;
        let at = ((x_first - x_lo - p as i64) / 2) as usize;
        let Resampler {
            y: ty,
            vertical,
            runs,
            skewed,
            ..
        } = r;
        let row = (y - y_lo) as usize;
        let first = i_lo as usize;
        let run = &mut skewed[row * w + first..][..len];
        let taps = |k: usize| {
            let tx = &runs[p][k];
            (
                (&tx.index[at..at + len], &tx.frac[at..at + len]),
                ty[k].at(row),
            )
        };
        let (tx, at_y) = taps(0);
        sample_row(&atlas.levels[l0], tx, at_y, vertical, run, None);
        if blend {
            let (tx, at_y) = taps(1);
            sample_row(&atlas.levels[l1], tx, at_y, vertical, run, Some(t));
        }
    }
    // Texel (i, j) is element i of lattice row j + a[1]·i, so along a region row texel i + 1
    // lies a[1]·w + 1 samples after texel i: walked as a slice's stride (from the last texel
    // where a[1] < 0), so that no read is checked.
    for (j, texels) in out[..n * n].chunks_exact_mut(n).enumerate() {
        let row_of_first = (j as i64 - y_lo) as usize;
        if a[1] > 0 {
            let walk = r.skewed[row_of_first * w..].iter().step_by(w + 1);
            texels.iter_mut().zip(walk).for_each(|(h, &v)| *h = v);
        } else {
            let last = row_of_first * w - (n - 1) * (w - 1);
            let walk = r.skewed[last..].iter().step_by(w - 1);
            texels.iter_mut().rev().zip(walk).for_each(|(h, &v)| *h = v);
        }
    }
}

/// The two mip levels around `spacing` and the weight of the coarser: trilinear sampling.
#[inline(always)]
fn levels(atlas: &Atlas, spacing: f64) -> (usize, usize, f32) {
    let top = atlas.levels.len() - 1;
    // A streamed sketch's finest levels are on the GPU only: the CPU reads the finest it holds.
    let lod = (spacing / atlas.d_atlas())
        .log2()
        .clamp(atlas.resident_from as f64, top as f64);
    let l0 = lod as usize;
    (l0, (l0 + 1).min(top), (lod - l0 as f64) as f32)
}

/// One output row of one level, from its taps along x and its source row and weight along y:
/// written to `row`, or blended into it by `blend`.
#[inline(always)]
fn sample_row(
    level: &crate::sketch::Level,
    (index, frac): (&[u32], &[f32]),
    (y, fy): (usize, f32),
    vertical: &mut Vec<f32>,
    row: &mut [f32],
    blend: Option<f32>,
) {
    let w = level.width;
    // Taps increase along x, so the span is from the first tap's texel to the last's right one.
    let (lo, hi) = (index[0] as usize, index[row.len() - 1] as usize + 2);
    let r0 = &level.data[y * w + lo..y * w + hi];
    let r1 = &level.data[(y + 1) * w + lo..(y + 1) * w + hi];
    vertical.clear();
    vertical.extend(r0.iter().zip(r1).map(|(&a, &b)| a + (b - a) * fy));
    let span = vertical.len();
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512()
        && (2..i32::MAX as usize - x86::WINDOW).contains(&span)
        && row.len() <= index.len().min(frac.len())
    {
        // Texels past the span, never a tap's, so that the last taps' windows lie inside too.
        vertical.resize(span + x86::WINDOW, 0.0);
        let taps = (&index[..row.len()], &frac[..row.len()]);
        // SAFETY: the processor has AVX-512F and AVX2, the span holds at least one pair and its
        // indices fit an i32, and there are as many taps as outputs, checked just above.
        unsafe { x86::taps((vertical, span), taps, lo, row, blend) };
        return;
    }
    taps(vertical, (index, frac), lo, row, blend);
}

/// The taps along x from the row of level texels `vertical` (texel `lo` first): each output
/// interpolated between its two texels, written to `row` or blended into it by `blend`.
#[inline(always)]
fn taps(
    vertical: &[f32],
    (index, frac): (&[u32], &[f32]),
    lo: usize,
    row: &mut [f32],
    blend: Option<f32>,
) {
    let at = |i: usize| {
        let k = index[i] as usize - lo;
        let f = frac[i];
        vertical[k] + (vertical[k + 1] - vertical[k]) * f
    };
    match blend {
        None => row.iter_mut().enumerate().for_each(|(i, h)| *h = at(i)),
        Some(t) => row
            .iter_mut()
            .enumerate()
            .for_each(|(i, h)| *h += (at(i) - *h) * t),
    }
}

/// The taps along x in AVX-512F: eight outputs at a time, each one's two texels (side by side
/// in the row) gathered as one 64-bit element and then parted, or permuted out of a window. The
/// same operations in the same order as [`taps`], so the same bits (`tests`). [`taps`] built for
/// AVX2 or AVX-512 by the compiler is slower still than [`taps`] as it is.
///
/// Where the eight taps' pairs lie within [`x86::WINDOW`] (32) texels of the first (a level's
/// texels are at least half the spacing, so a step is at most about two texels), they come from
/// two loads and two permutes instead of a gather; elsewhere (a region coarser than the coarsest
/// level) from the gather. The row of texels is padded by a window, so that the row's last taps
/// take the loads too; windows of 16 texels without the padding would leave the row's last
/// blocks and a wider step to the gather (docs/decisions.md, “Sketch map resampling”).
#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    /// Texels loaded at once for eight taps' pairs.
    pub const WINDOW: usize = 32;

    /// The row of texels is `padded[..span]`; the texels after it are read in windows but
    /// never used.
    ///
    /// # Safety
    /// The processor must have AVX-512F and AVX2; `span` is at least 2, at most `padded`'s
    /// length, which is below 2^31; `index` and `frac` as many as `row`. Each pair read is
    /// clamped into the span, so taps that do not increase along x (which [`Taps::fill`] never
    /// gives) read wrong texels but none outside it.
    ///
    /// [`Taps::fill`]: super::Taps
    #[target_feature(enable = "avx512f,avx2")]
    pub unsafe fn taps(
        (padded, span): (&[f32], usize),
        (index, frac): (&[u32], &[f32]),
        lo: usize,
        row: &mut [f32],
        blend: Option<f32>,
    ) {
        const L: usize = 8;
        let n = row.len();
        debug_assert!(index.len() == n && frac.len() == n && span >= 2 && padded.len() >= span);
        let whole = n / L * L;
        let (lo_v, top) = (
            _mm256_set1_epi32(lo as i32),
            _mm256_set1_epi32(span as i32 - 2),
        );
        let parting = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15);
        let t = _mm256_set1_ps(blend.unwrap_or(0.0));
        for i in (0..whole).step_by(L) {
            // SAFETY: i + L ≤ n, the length of `index`, `frac` and `row`; each pair's first
            // texel is clamped to span − 2 (taps increase along x, so it never binds), so the
            // pair lies inside the span; a window's loads are checked to lie inside `padded`.
            unsafe {
                let k = _mm256_loadu_si256(index.as_ptr().add(i).cast());
                let k = _mm256_min_epi32(
                    _mm256_max_epi32(_mm256_sub_epi32(k, lo_v), _mm256_setzero_si256()),
                    top,
                );
                let k0 = _mm256_cvtsi256_si32(k) as usize;
                let k7 = _mm256_extract_epi32::<7>(k) as usize;
                let (v0, v1) = if k7 + 1 < k0 + WINDOW && k0 + WINDOW <= padded.len() {
                    // The eight pairs lie in the WINDOW texels from the first: two loads and
                    // two permutes in place of a gather.
                    let window = padded.as_ptr().add(k0);
                    let (w0, w1) = (
                        _mm512_loadu_ps(window),
                        _mm512_loadu_ps(window.add(WINDOW / 2)),
                    );
                    let rel =
                        _mm512_castsi256_si512(_mm256_sub_epi32(k, _mm256_set1_epi32(k0 as i32)));
                    let v0 = _mm512_permutex2var_ps(w0, rel, w1);
                    let v1 =
                        _mm512_permutex2var_ps(w0, _mm512_add_epi32(rel, _mm512_set1_epi32(1)), w1);
                    (_mm512_castps512_ps256(v0), _mm512_castps512_ps256(v1))
                } else {
                    let pairs =
                        _mm512_castpd_ps(_mm512_i32gather_pd::<4>(k, padded.as_ptr().cast()));
                    let parted = _mm512_permutexvar_ps(parting, pairs);
                    (
                        _mm512_castps512_ps256(parted),
                        _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(parted))),
                    )
                };
                let f = _mm256_loadu_ps(frac.as_ptr().add(i));
                let v = _mm256_add_ps(v0, _mm256_mul_ps(_mm256_sub_ps(v1, v0), f));
                let at = row.as_mut_ptr().add(i);
                let v = if blend.is_some() {
                    let h = _mm256_loadu_ps(at);
                    _mm256_add_ps(h, _mm256_mul_ps(_mm256_sub_ps(v, h), t))
                } else {
                    v
                };
                _mm256_storeu_ps(at, v);
            }
        }
        let rest = (&index[whole..], &frac[whole..]);
        super::taps(&padded[..span], rest, lo, &mut row[whole..], blend);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX-512 taps give the scalar loop's bits: rows of 128 and of 37 (a remainder past
    /// the last eight), written and blended, each with its row of texels ending at the last
    /// tap's pair and with it padded as `sample_row` pads it (NaN padding, which must not
    /// show). The taps: random steps of up to 1.3 texels (every window fits), up to 6 (some do
    /// not), and blocks placed by hand with eight taps' pairs over 30, 31, 32 and 33 texels (the
    /// window holds 32) and on one pair.
    #[test]
    fn every_build_of_the_taps_gives_the_same_bits() {
        #[cfg(target_arch = "x86_64")]
        if crate::stage::simd::avx512() {
            let mut next = crate::stage::lines::tests::uniform(0x1b87_3593);
            let mut random = |n: usize, step: f32| {
                let mut c = 0.0f32;
                (0..n)
                    .map(|_| {
                        c += step * next();
                        (c as u32, c.fract())
                    })
                    .collect::<Vec<_>>()
            };
            let mut by_hand = vec![];
            let mut k0 = 0;
            // The last tap's offset: pairs over 30, 31, 32 and 33 texels, then eight taps on
            // one pair.
            for last in [28, 29, 30, 31, 0] {
                for (l, d) in [0, 1, 1, 2, 5, 9, 20, last].into_iter().enumerate() {
                    let d = if last == 0 { 0 } else { d };
                    by_hand.push((k0 + d, 0.25 + l as f32 / 16.0));
                }
                k0 += last + 1;
            }
            let cases = [random(128, 1.3), random(37, 1.3), random(128, 6.0), by_hand];
            let mut next = crate::stage::lines::tests::uniform(0x2c1b_3c6d);
            for (case, tapped) in cases.iter().enumerate() {
                let n = tapped.len();
                let lo = 11;
                let (index, frac): (Vec<u32>, Vec<f32>) =
                    tapped.iter().map(|&(k, f)| (k + lo as u32, f)).unzip();
                let span = index[n - 1] as usize - lo + 2;
                let vertical: Vec<f32> = (0..span).map(|_| 4000.0 * next() - 200.0).collect();
                let mut padded = vertical.clone();
                padded.resize(span + x86::WINDOW, f32::NAN);
                for blend in [None, Some(0.37)] {
                    let start: Vec<f32> = (0..n).map(|_| 900.0 * next()).collect();
                    let mut want = start.clone();
                    taps(&vertical, (&index, &frac), lo, &mut want, blend);
                    for row in [&vertical, &padded] {
                        let mut got = start.clone();
                        // SAFETY: the processor has AVX-512F and AVX2; lengths as it asks.
                        unsafe { x86::taps((row, span), (&index, &frac), lo, &mut got, blend) };
                        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        let at = format!("case {case} blend {blend:?} padded {}", row.len());
                        assert_eq!(bits(&got), bits(&want), "{at}");
                        assert!(got.iter().any(|&v| v != got[0]), "{at}");
                    }
                }
            }
            return;
        }
        eprintln!(
            "skipped: the processor lacks AVX-512F or AVX2, so the scalar taps are all it runs"
        );
    }
}
