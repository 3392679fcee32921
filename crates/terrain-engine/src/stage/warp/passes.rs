//! The warp's passes: the row pass, each column from its own mapping, every column from the mean
//! one, and the importance's gradient limit before them. Each pass is `#[inline(always)]`, so
//! that it is built into `run`'s AVX-512 and AVX2 builds; a group's last, partial lanes are
//! stored by `store_kept` or, where LLVM would merge the branches into a memcpy call, apart.

use super::{Warp, pair_unfolded, pairs_unfolded};
use crate::scene::WarpMethod;
use crate::stage::lines::{
    LANES, LaneLines, column_points, lane_mappings, lerp_at, lerp_lanes, lerp_weight, line_mapping,
    row_samples,
};

impl Warp {
    #[inline(always)]
    pub(super) fn run_lanes(&mut self, importance: &[f32], d0: f32) {
        let n = self.n;
        assert_eq!(importance.len(), n * n, "importance map size");
        if self.max_log2_step > 0.0 {
            // Taken out of self for the row pass, which borrows self mutably.
            let mut limited = std::mem::take(&mut self.limited);
            limited.resize(n * n, 0.0);
            limited.copy_from_slice(importance);
            limit_gradient(&mut limited, n, (-self.max_log2_step).exp2());
            self.row_pass(&limited, d0);
            self.limited = limited;
        } else {
            self.row_pass(importance, d0);
        }
        self.follows_mean.fill(false);
        self.guarded_columns = 0;
        let guarded = self.method == WarpMethod::Guarded;
        // Eight columns at a time, so that the guard's count of folded pairs (kept in column
        // order but for the first group's) can stop the pass as soon as `fallback_pairs` have
        // folded: every column then follows the mean, whatever the rest would do.
        let mut folded = 0;
        // The first group's pairs wait for the second group's first column, so that they too
        // are checked eight at once.
        let first_later = n > LANES;
        for s0 in (0..n).step_by(LANES) {
            self.map_columns(s0, d0);
            if !guarded || (s0 == 0 && first_later) {
                continue;
            }
            if s0 == LANES {
                let sound = pairs_unfolded(&self.phi, n, 0);
                for (pair, &unfolded) in sound.iter().enumerate().take(LANES - 1) {
                    if self.tally_pair(pair, unfolded, &mut folded) {
                        self.all_to_mean(d0);
                        return;
                    }
                }
            }
            // The pairs left of each new column; eight at once where they are all inside.
            let sound = (s0 >= 1 && s0 + LANES <= n).then(|| pairs_unfolded(&self.phi, n, s0 - 1));
            for s in s0.max(1)..(s0 + LANES).min(n) {
                let unfolded = match sound {
                    Some(sound) => sound[s - s0],
                    None => pair_unfolded(&self.phi, n, s - 1),
                };
                if self.tally_pair(s - 1, unfolded, &mut folded) {
                    self.all_to_mean(d0);
                    return;
                }
            }
        }
        if guarded && folded > 0 {
            self.mean_mapping();
            self.guard(d0);
        }
    }
    /// The mean column mapping `b̄`: that of the row-warped importance summed across columns.
    /// Made only where a fold needs it (none folds on most high views).
    #[inline(always)]
    fn mean_mapping(&mut self) {
        let n = self.n;
        self.mean_importance.fill(0.0);
        for s in 0..n {
            let line = &self.row_importance[s * n..(s + 1) * n];
            for (m, &v) in self.mean_importance.iter_mut().zip(line) {
                *m += v;
            }
        }
        line_mapping(&self.mean_importance, &mut self.scratch, &mut self.mean_map);
    }

    /// Every column to the mean column warp (near views, where more than an eighth of the column
    /// pairs fold).
    #[inline(always)]
    fn all_to_mean(&mut self, d0: f32) {
        self.mean_mapping();
        self.follows_mean.fill(true);
        let n = self.n;
        // Every lane reads the same two samples of its column, so the columns go side by side
        // and each output row is a plain interpolation of two rows of lanes, cheaper than
        // gathering them (`store_columns`, as a column with its own mapping must).
        for s0 in (0..n).step_by(LANES) {
            side_by_side(&self.row_x, n, s0, &mut self.lanes_in);
            let kept = LANES.min(n - s0);
            for (t, &b) in self.mean_map.iter().enumerate() {
                let (i, f) = lerp_weight(b, n);
                let (lo, hi) = (self.lanes_in[i], self.lanes_in[i + 1]);
                let y = (b * d0 as f64) as f32;
                let p: [[f32; 2]; LANES] =
                    std::array::from_fn(|l| [lo[l] + (hi[l] - lo[l]) * f, y]);
                store_kept_apart(&mut self.phi[t * n + s0..], &p, kept);
            }
        }
        self.guarded_columns = n;
    }

    #[inline(always)]
    fn row_pass(&mut self, importance: &[f32], d0: f32) {
        let n = self.n;
        for t0 in (0..n).step_by(LANES) {
            side_by_side(importance, n, t0, &mut self.lanes_in);
            lane_mappings(&self.lanes_in, &mut self.lanes, &mut self.lanes_out);
            let kept = LANES.min(n - t0);
            let lines = LaneLines::new(importance, n, t0);
            if kept == LANES {
                let (x, v) = (&mut self.row_x, &mut self.row_importance);
                if row_samples(importance, &lines, &self.lanes_out, d0, x, v, t0) {
                    continue;
                }
            }
            for (s, a) in self.lanes_out.iter().enumerate() {
                let x = a.map(|a| (a * d0 as f64) as f32);
                let v = lerp_lanes(importance, &lines, a);
                let at = s * n + t0;
                store_kept(&mut self.row_x[at..], &x, kept);
                store_kept(&mut self.row_importance[at..], &v, kept);
            }
        }
    }

    /// Columns `s0 ..` of Φ (as many as there are lanes, or to the last column), each from its
    /// own column mapping.
    #[inline(always)]
    fn map_columns(&mut self, s0: usize, d0: f32) {
        let n = self.n;
        side_by_side(&self.row_importance, n, s0, &mut self.lanes_in);
        lane_mappings(&self.lanes_in, &mut self.lanes, &mut self.lanes_out);
        let maps = &self.lanes_out;
        if s0 + LANES <= n {
            let lines = LaneLines::new(&self.row_x, n, s0);
            if column_points(&self.row_x, &lines, maps, d0, &mut self.phi, s0) {
                return;
            }
        }
        store_columns(&mut self.phi, &self.row_x, n, s0, d0, |t| maps[t]);
    }

    /// Column s of Φ from the mean column mapping (the guard's).
    #[inline(always)]
    pub(super) fn column_pass(&mut self, s: usize, d0: f32) {
        let n = self.n;
        let xs = &self.row_x[s * n..][..n];
        for (t, &b) in self.mean_map.iter().enumerate() {
            self.phi[t * n + s] = [lerp_at(xs, b), (b * d0 as f64) as f32];
        }
    }
}

/// Columns `s0 ..` of Φ (as many as there are lanes, or to the last column): each lane's
/// row-warped x (`row_x`, column-major) interpolated at `b(t)`, its column mapping's output t.
#[inline(always)]
fn store_columns(
    phi: &mut [[f32; 2]],
    row_x: &[f32],
    n: usize,
    s0: usize,
    d0: f32,
    b: impl Fn(usize) -> [f64; LANES],
) {
    let kept = LANES.min(n - s0);
    let lines = LaneLines::new(row_x, n, s0);
    for t in 0..n {
        let b = b(t);
        let x = lerp_lanes(row_x, &lines, &b);
        let p: [[f32; 2]; LANES] = std::array::from_fn(|l| [x[l], (b[l] * d0 as f64) as f32]);
        store_kept_apart(&mut phi[t * n + s0..], &p, kept);
    }
}

/// Lines `first ..` of `buf` (lines of `n` samples, one after another) side by side:
/// `lanes[i][l]` is sample i of line `first + l`. Lanes past the last line repeat it; their
/// results are not kept.
#[inline(always)]
fn side_by_side(buf: &[f32], n: usize, first: usize, lanes: &mut [[f32; LANES]]) {
    let lines: [&[f32]; LANES] = std::array::from_fn(|l| &buf[(first + l).min(n - 1) * n..][..n]);
    for (i, v) in lanes.iter_mut().enumerate() {
        for l in 0..LANES {
            v[l] = lines[l][i];
        }
    }
}

/// The first `kept` lanes of `v` to the start of `dst`.
#[inline(always)]
fn store_kept<T: Copy>(dst: &mut [T], v: &[T; LANES], kept: usize) {
    if kept == LANES {
        // A fixed-size copy: a slice of run-time length calls memmove.
        dst[..LANES].copy_from_slice(v);
    } else {
        dst[..kept].copy_from_slice(&v[..kept]);
    }
}

/// [`store_kept`] for `all_to_mean`, with the last group's copy of run-time length a call apart:
/// inline, LLVM merges the two branches there into one memcpy of `kept` lanes, called for every
/// group; `store_columns` too (the module doc). In the row pass the merged copy is inlined and
/// the faster.
#[inline(always)]
fn store_kept_apart<T: Copy>(dst: &mut [T], v: &[T; LANES], kept: usize) {
    if kept == LANES {
        let dst: &mut [T; LANES] = (&mut dst[..LANES]).try_into().expect("LANES values");
        *dst = *v;
    } else {
        store_part(dst, v, kept);
    }
}

#[cold]
#[inline(never)]
fn store_part<T: Copy>(dst: &mut [T], v: &[T; LANES], kept: usize) {
    dst[..kept].copy_from_slice(&v[..kept]);
}

/// Raises every value to at least `factor` × each 4-neighbour's (an L1 chamfer in log space).
fn limit_gradient(v: &mut [f32], n: usize, factor: f32) {
    for j in 0..n {
        for i in 0..n {
            let mut x = v[j * n + i];
            if i > 0 {
                x = x.max(v[j * n + i - 1] * factor);
            }
            if j > 0 {
                x = x.max(v[(j - 1) * n + i] * factor);
            }
            v[j * n + i] = x;
        }
    }
    for j in (0..n).rev() {
        for i in (0..n).rev() {
            let mut x = v[j * n + i];
            if i + 1 < n {
                x = x.max(v[j * n + i + 1] * factor);
            }
            if j + 1 < n {
                x = x.max(v[(j + 1) * n + i] * factor);
            }
            v[j * n + i] = x;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_limit_bounds_every_step() {
        let n = 16;
        let mut v = vec![1e-6f32; n * n];
        v[5 * n + 7] = 1e6;
        limit_gradient(&mut v, n, 0.5);
        for j in 0..n {
            for i in 0..n - 1 {
                let (a, b) = (v[j * n + i], v[j * n + i + 1]);
                assert!(a.max(b) / a.min(b) <= 2.0 + 1e-4);
            }
        }
        assert_eq!(v[5 * n + 7], 1e6);
    }
}
