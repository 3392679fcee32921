//! The fold guard and its check: whether a pair of Φ's columns folds (one pair, eight at once, in
//! AVX-512F where the processor has it), the count that decides the all-mean shortcut, and the
//! guard's rounds. A cell is sound when both its triangles turn counter-clockwise and its bottom
//! and top edges run east (`cell_turn`); the kernels give the plain Rust's results.

use super::Warp;
use crate::stage::lines::LANES;

impl Warp {
    /// Records whether the columns `pair`, `pair + 1` fold and counts it; true once the count
    /// reaches `fallback_pairs`. The order in which pairs are counted changes only when the
    /// count is reached, never whether it is.
    #[inline(always)]
    pub(super) fn tally_pair(&mut self, pair: usize, unfolded: bool, folded: &mut usize) -> bool {
        self.folded[pair] = !unfolded;
        *folded += usize::from(!unfolded);
        *folded >= self.fallback_pairs
    }
    /// Sends the columns beside every folded cell (`folded`, set by the column pass) to the mean
    /// column warp, until no triangle of the mesh is flipped. Each round moves at least one more
    /// column, so it ends.
    #[inline(always)]
    pub(super) fn guard(&mut self, d0: f32) {
        let n = self.n;
        loop {
            self.changed.fill(false);
            for s in 0..n - 1 {
                if self.folded[s] {
                    for c in s.saturating_sub(1)..=(s + 2).min(n - 1) {
                        self.changed[c] = !self.follows_mean[c];
                    }
                }
            }
            if !self.changed.contains(&true) {
                // No fold left, or only between columns that both follow the mean: none, by the
                // trapezoid argument above, unless rounding breaks it (then nothing more can help).
                break;
            }
            for s in 0..n {
                if self.changed[s] {
                    self.follows_mean[s] = true;
                    self.column_pass(s, d0);
                }
            }
            for s in 0..n - 1 {
                if self.changed[s] || self.changed[s + 1] {
                    self.folded[s] = !pair_unfolded(&self.phi, n, s);
                }
            }
        }
        self.guarded_columns = self.follows_mean.iter().filter(|&&m| m).count();
    }
}
/// Whether every cell between columns s and s+1 of Φ is sound (see `cell_turn`).
#[inline(always)]
pub fn pair_unfolded(phi: &[[f32; 2]], n: usize, s: usize) -> bool {
    let mut least = f32::INFINITY;
    for t in 0..n - 1 {
        least = least.min(cell_turn(phi, n, s, t));
    }
    least > 0.0
}

/// [`pair_unfolded`] for the [`LANES`] pairs of columns `s ..= s + LANES − 1`, side by side.
#[inline(always)]
pub fn pairs_unfolded(phi: &[[f32; 2]], n: usize, s: usize) -> [bool; LANES] {
    // Every point the pairs read, so that the kernel's reads are in bounds.
    assert!(
        s + LANES < n && phi.len() >= n * n,
        "pairs {s}.. of {n} columns"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() {
        // SAFETY: the processor has AVX-512F and AVX2; the points, checked just above.
        return unsafe { x86::pairs_unfolded(phi, n, s) };
    }
    pairs_unfolded_lanes(phi, n, s)
}

/// [`pairs_unfolded`] as plain Rust (and the record of what the AVX-512 kernel computes).
#[inline(always)]
fn pairs_unfolded_lanes(phi: &[[f32; 2]], n: usize, s: usize) -> [bool; LANES] {
    let mut least = [f32::INFINITY; LANES];
    let row = |t: usize| -> &[[f32; 2]; LANES + 1] {
        phi[t * n + s..][..LANES + 1]
            .try_into()
            .expect("LANES + 1 points")
    };
    // Rows in blocks, so that a block where every pair has folded already ends the check (near
    // views, where most do, early), and the test stays out of the vectorised inner loop.
    const BLOCK: usize = 16;
    for t0 in (0..n - 1).step_by(BLOCK) {
        for t in t0..(t0 + BLOCK).min(n - 1) {
            let (lo, hi) = (row(t), row(t + 1));
            for l in 0..LANES {
                let turn = turn_of(lo[l], lo[l + 1], hi[l + 1], hi[l]);
                // Never NaN for finite Φ; a NaN leaves the pair as it was, as f32::min would.
                if turn < least[l] {
                    least[l] = turn;
                }
            }
        }
        if least.iter().all(|&t| t <= 0.0) {
            break;
        }
    }
    least.map(|t| t > 0.0)
}

/// [`pairs_unfolded_lanes`] in AVX-512F: each row's eight points and the eight beside them,
/// loaded whole and parted into x and y, so that the eight turns are plain vector arithmetic
/// (interleaved points leave the lane loop to shuffles). The same turns; where the plain Rust
/// keeps the least of each cell's four values, NaN passed over, and asks whether it is positive,
/// the kernel ors each value's `≤ 0` (false for NaN) into a lane's fold: the same answer for any
/// input, four comparisons and ors where `f32::min` takes a minimum, a NaN test and a blend for
/// each. Rejected: the check
/// made in `store_columns` from the points in registers as they are stored, slower
/// (docs/decisions.md, “Warp in lanes of eight”).
#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::LANES;
    use std::arch::x86_64::*;

    /// # Safety
    /// The processor must have AVX-512F and AVX2; `phi` holds n rows of n points and
    /// `s + LANES < n`.
    #[target_feature(enable = "avx512f,avx2")]
    pub unsafe fn pairs_unfolded(phi: &[[f32; 2]], n: usize, s: usize) -> [bool; LANES] {
        debug_assert!(s + LANES < n && phi.len() >= n * n);
        let base = phi.as_ptr().cast::<f32>();
        let parting = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15);
        // Row t's points s.. (`left`) and s + 1.. (`right`), each as (x, y) lanes.
        // SAFETY: both spans, 16 floats from point s or s + 1 of row t < n, end at or before
        // point s + LANES of that row, inside Φ.
        let row = |t: usize| unsafe {
            let at = base.add(2 * (t * n + s));
            let part = |v: __m512| {
                let v = _mm512_permutexvar_ps(parting, v);
                let hi = _mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v));
                (_mm512_castps512_ps256(v), _mm256_castpd_ps(hi))
            };
            (part(_mm512_loadu_ps(at)), part(_mm512_loadu_ps(at.add(2))))
        };
        // All ones in the lanes of a pair with a cell value ≤ 0 so far.
        let zero = _mm256_setzero_ps();
        let at_most_zero = |v: __m256| _mm256_cmp_ps::<_CMP_LE_OQ>(v, zero);
        let mut folded = zero;
        let mut lo = row(0);
        const BLOCK: usize = 16;
        'blocks: for t0 in (0..n - 1).step_by(BLOCK) {
            for t in t0..(t0 + BLOCK).min(n - 1) {
                let hi = row(t + 1);
                // Corners a (s, t), b (s+1, t), c (s+1, t+1), d (s, t+1), as turn_of's.
                let ((ax, ay), (bx, by)) = lo;
                let ((dx, dy), (cx, cy)) = hi;
                let turn = |px, py, qx, qy, rx, ry| {
                    let u = _mm256_mul_ps(_mm256_sub_ps(qx, px), _mm256_sub_ps(ry, qy));
                    let v = _mm256_mul_ps(_mm256_sub_ps(qy, py), _mm256_sub_ps(rx, qx));
                    _mm256_sub_ps(u, v)
                };
                let abc = turn(ax, ay, bx, by, cx, cy);
                let cda = turn(cx, cy, dx, dy, ax, ay);
                let turns = _mm256_or_ps(at_most_zero(abc), at_most_zero(cda));
                let edges = _mm256_or_ps(
                    at_most_zero(_mm256_sub_ps(bx, ax)),
                    at_most_zero(_mm256_sub_ps(cx, dx)),
                );
                folded = _mm256_or_ps(folded, _mm256_or_ps(turns, edges));
                lo = hi;
            }
            if _mm256_movemask_ps(folded) == 0xff {
                break 'blocks;
            }
        }
        let folded = _mm256_movemask_ps(folded);
        std::array::from_fn(|l| folded & (1 << l) == 0)
    }
}

/// Positive when cell (s, t) is sound: neither of its two triangles (split along the diagonal
/// from (s, t) to (s+1, t+1), as the mesh is drawn unless the cell is convex: `lod::warped::mesh_split`)
/// is flipped or degenerate, and its bottom and
/// top edges run east, so every row of Φ increases in x as every column increases in y.
/// Only the sign means anything. f32 suffices: edges are at least 1/(n−1) of a texel long,
/// coordinates at most n texels.
#[inline(always)]
pub fn cell_turn(phi: &[[f32; 2]], n: usize, s: usize, t: usize) -> f32 {
    turn_of(
        phi[t * n + s],
        phi[t * n + s + 1],
        phi[(t + 1) * n + s + 1],
        phi[(t + 1) * n + s],
    )
}

/// [`cell_turn`] of the cell with corners a (s, t), b (s+1, t), c (s+1, t+1), d (s, t+1).
#[inline(always)]
fn turn_of(a: [f32; 2], b: [f32; 2], c: [f32; 2], d: [f32; 2]) -> f32 {
    let turn = |p: [f32; 2], q: [f32; 2], r: [f32; 2]| {
        (q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0])
    };
    turn(a, b, c)
        .min(turn(c, d, a))
        .min(b[0] - a[0])
        .min(c[0] - d[0])
}

/// Signed area of cell (s, t) of Φ (shoelace), positive counter-clockwise.
pub fn cell_area(phi: &[[f32; 2]], n: usize, s: usize, t: usize) -> f64 {
    let p = [
        phi[t * n + s],
        phi[t * n + s + 1],
        phi[(t + 1) * n + s + 1],
        phi[(t + 1) * n + s],
    ];
    0.5 * (0..4)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % 4]);
            a[0] as f64 * b[1] as f64 - b[0] as f64 * a[1] as f64
        })
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stage::warp::tests::random_map;

    /// The pair check (the lanes, the AVX-512 kernel and the dispatch between them) gives what
    /// the one-pair check gives, on grids whose rows 5 and 17 are shaken in x by up to ±0.6 of a
    /// cell (the columns where neighbours cross fold, the others do not); and on wavy ones, also
    /// shaken in row n − 3 (folds after the first block of rows, which the block exit must not
    /// skip), some with NaN points.
    #[test]
    fn every_build_of_the_pair_check_agrees() {
        #[cfg(target_arch = "x86_64")]
        if !crate::stage::simd::avx512() {
            eprintln!("skipped: the AVX-512 check (no AVX-512F here); the lanes alone are checked");
        }
        for (n, seed, wavy, nan) in [
            (40, 3, false, false),
            (40, 3, true, false),
            (40, 5, true, true),
            (128, 9, true, false),
            (128, 11, true, true),
        ] {
            let shake = random_map(n, seed);
            let phi: Vec<[f32; 2]> = (0..n * n)
                .map(|k| {
                    let (s, t) = (k % n, k / n);
                    let dx = if t == 5 || t == 17 || (wavy && t == n - 3) {
                        shake[k].log10() / 10.0
                    } else {
                        0.0
                    };
                    let wave = if wavy {
                        0.3 * (s as f32 * 0.7).sin()
                    } else {
                        0.0
                    };
                    let y = t as f32 + wave;
                    if nan && (k % 97 == 13 || k % 89 == 2) {
                        [f32::NAN, y]
                    } else {
                        [s as f32 + dx, y]
                    }
                })
                .collect();
            let folded = (0..n - 1).filter(|&s| !pair_unfolded(&phi, n, s)).count();
            assert!(folded > 0 && folded < n - 1, "n {n}: some folds: {folded}");
            for s in 0..n - LANES {
                let lanes = pairs_unfolded_lanes(&phi, n, s);
                for (l, &sound) in lanes.iter().enumerate() {
                    assert_eq!(sound, pair_unfolded(&phi, n, s + l), "n {n} pair {}", s + l);
                }
                assert_eq!(pairs_unfolded(&phi, n, s), lanes, "n {n} pairs from {s}");
                #[cfg(target_arch = "x86_64")]
                if crate::stage::simd::avx512() {
                    // SAFETY: the processor has AVX-512F and AVX2; s + LANES < n.
                    let wide = unsafe { x86::pairs_unfolded(&phi, n, s) };
                    assert_eq!(wide, lanes, "n {n} pairs from {s}");
                }
            }
        }
    }
    /// One flipped triangle whose cell's other corner is NaN: f32::min keeps the flipped turn
    /// over the NaN one, so the pair is folded in every build (a bare vminps would keep the NaN
    /// and then the positive edge, and call it sound).
    #[test]
    fn a_flip_beside_a_nan_corner_folds_its_pair() {
        let n = 16;
        let mut phi: Vec<[f32; 2]> = (0..n * n)
            .map(|k| [(k % n) as f32, (k / n) as f32])
            .collect();
        phi[3 * n + 3] = [3.0, 4.5]; // b of cell (2, 3): its triangle a, b, c turns clockwise
        phi[4 * n + 2] = [f32::NAN, 4.0]; // d of cell (2, 3)
        assert!(!pair_unfolded(&phi, n, 2));
        assert!(!pairs_unfolded_lanes(&phi, n, 0)[2]);
        assert!(!pairs_unfolded(&phi, n, 0)[2]);
    }
}
