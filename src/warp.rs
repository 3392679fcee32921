//! The warp: a row pass then a column pass over the sketch map's geometry image, moving its samples
//! so that each segment gets output room in proportion to its importance (DESIGN.md's definition).
//!
//! Rules:
//! - One line: weights `w_i = (I_i + I_{i+1})/2`, positions `u` their running sum scaled to `n−1`,
//!   output sample j interpolated inside the segment holding `u = j`. A line's result is a
//!   *mapping*: the fractional source index of each output sample, monotone, 0 and n−1 at the ends.
//! - The row pass warps x along each row and resamples importance the same way; the column pass
//!   warps each column of the row-warped image by that resampled importance.
//! - `Plain` stops there: the paper's method. Where neighbouring columns want very different column
//!   warps and the rows under them were warped differently too, cells fold.
//! - `Guarded` (the default) keeps every cell strictly convex. Column s's mapping becomes
//!   `b̄ + λ_s·(b_s − b̄)`, with `b̄` the mapping of the row-averaged importance. With λ = 1 this is the
//!   plain warp; with λ = 0 on both sides of a cell the cell is a trapezoid between two rows of equal
//!   y and cannot fold. So halving λ around each folded cell, and zeroing it after a few halvings,
//!   ends with no fold in a bounded number of rounds, and columns without folds keep the plain warp.
//! - An optional limit on the importance gradient (`max_log2_step`) raises low importance next to
//!   high, in log space, before warping: fewer folds to guard, at the cost of spreading cells.
//! - All buffers are allocated once in [`Warp::new`]; a frame allocates nothing.
//!
//! Rejected alternatives: extra row/column passes over the warped image (the grid is no longer
//! axis-aligned, and a second pass can fold what the first left intact) and always smoothing the
//! importance (it lowers the density ratio everywhere to fix folds that occur in a few places).

use crate::scene::WarpMethod;

/// Halvings of a column's λ before it is set to 0.
const MAX_HALVINGS: u32 = 5;

pub struct Warp {
    n: usize,
    pub method: WarpMethod,
    /// Largest log2 step of importance between 4-neighbours; 0: no limit.
    pub max_log2_step: f32,
    importance: Vec<f32>,
    u: Vec<f64>,
    line: Vec<f64>,
    row_x: Vec<f32>,
    row_importance: Vec<f32>,
    column_maps: Vec<f64>,
    mean_importance: Vec<f32>,
    mean_map: Vec<f64>,
    lambda: Vec<f32>,
    halvings: Vec<u32>,
    changed: Vec<bool>,
    /// Φ: output (s, t) → region-local (x, y) metres, row-major with t the row.
    pub phi: Vec<[f32; 2]>,
    /// Columns whose warp the guard relaxed in the last frame.
    pub guarded_columns: usize,
}

impl Warp {
    pub fn new(n: usize, method: WarpMethod, max_log2_step: f32) -> Warp {
        Warp {
            n,
            method,
            max_log2_step,
            importance: vec![0.0; n * n],
            u: vec![0.0; n],
            line: vec![0.0; n],
            row_x: vec![0.0; n * n],
            row_importance: vec![0.0; n * n],
            column_maps: vec![0.0; n * n],
            mean_importance: vec![0.0; n],
            mean_map: vec![0.0; n],
            lambda: vec![1.0; n],
            halvings: vec![0; n],
            changed: vec![false; n],
            phi: vec![[0.0; 2]; n * n],
            guarded_columns: 0,
        }
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Warps the n² grid of spacing `d0` (region-local: texel (i, j) at (i·d0, j·d0)) by
    /// `importance` (n², row-major). The result is in [`Warp::phi`].
    pub fn run(&mut self, importance: &[f32], d0: f32) {
        let n = self.n;
        assert_eq!(importance.len(), n * n, "importance map size");
        self.importance.copy_from_slice(importance);
        if self.max_log2_step > 0.0 {
            limit_gradient(&mut self.importance, n, (-self.max_log2_step).exp2());
        }
        self.row_pass(d0);
        for s in 0..n {
            line_mapping(
                |t| self.row_importance[t * n + s],
                &mut self.u,
                &mut self.column_maps[s * n..(s + 1) * n],
            );
        }
        self.lambda.fill(1.0);
        self.halvings.fill(0);
        self.guarded_columns = 0;
        if self.method == WarpMethod::Guarded {
            for t in 0..n {
                let row = &self.row_importance[t * n..(t + 1) * n];
                self.mean_importance[t] = row.iter().sum::<f32>() / n as f32;
            }
            let mean = &self.mean_importance;
            line_mapping(|t| mean[t], &mut self.u, &mut self.mean_map);
        }
        for s in 0..n {
            self.column_pass(s, d0);
        }
        if self.method == WarpMethod::Guarded {
            self.guard(d0);
        }
    }

    fn row_pass(&mut self, d0: f32) {
        let n = self.n;
        for t in 0..n {
            let row = &self.importance[t * n..(t + 1) * n];
            line_mapping(|i| row[i], &mut self.u, &mut self.line);
            for s in 0..n {
                let a = self.line[s];
                self.row_x[t * n + s] = (a * d0 as f64) as f32;
                self.row_importance[t * n + s] = lerp_at(row, a);
            }
        }
    }

    /// Column s of Φ from its mapping, blended toward the mean mapping by λ_s.
    fn column_pass(&mut self, s: usize, d0: f32) {
        let n = self.n;
        let lambda = self.lambda[s] as f64;
        for t in 0..n {
            let own = self.column_maps[s * n + t];
            let b = if lambda == 1.0 {
                own
            } else {
                let m = self.mean_map[t];
                m + lambda * (own - m)
            };
            let r = (b.floor() as usize).min(n - 2);
            let f = (b - r as f64) as f32;
            let (x0, x1) = (self.row_x[r * n + s], self.row_x[(r + 1) * n + s]);
            self.phi[t * n + s] = [x0 + (x1 - x0) * f, (b * d0 as f64) as f32];
        }
    }

    /// Relaxes columns around folded cells until every cell is strictly convex.
    fn guard(&mut self, d0: f32) {
        let n = self.n;
        loop {
            self.changed.fill(false);
            for s in 0..n - 1 {
                if (0..n - 1).any(|t| !cell_convex(&self.phi, n, s, t)) {
                    for c in s.saturating_sub(1)..=(s + 2).min(n - 1) {
                        self.changed[c] = true;
                    }
                }
            }
            let mut progressed = false;
            for s in 0..n {
                if self.changed[s] && self.lambda[s] > 0.0 {
                    self.halvings[s] += 1;
                    self.lambda[s] = if self.halvings[s] > MAX_HALVINGS {
                        0.0
                    } else {
                        0.5f32.powi(self.halvings[s] as i32)
                    };
                    self.column_pass(s, d0);
                    progressed = true;
                }
            }
            // No fold left, or every column at a fold already follows the mean (which cannot fold).
            if !progressed {
                break;
            }
        }
        self.guarded_columns = self.lambda.iter().filter(|&&l| l < 1.0).count();
    }
}

/// Fractional source index of each output sample of one line with importance `imp(i)`.
/// Non-finite or negative importance counts as 0; a line with no weight at all stays put.
pub fn line_mapping(imp: impl Fn(usize) -> f32, u: &mut [f64], out: &mut [f64]) {
    let n = out.len();
    let weight = |v: f32| {
        if v.is_finite() && v > 0.0 {
            v as f64
        } else {
            0.0
        }
    };
    u[0] = 0.0;
    let mut prev = weight(imp(0));
    for i in 0..n - 1 {
        let next = weight(imp(i + 1));
        u[i + 1] = u[i] + 0.5 * (prev + next);
        prev = next;
    }
    let total = u[n - 1];
    if !(total > 0.0 && total.is_finite()) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = j as f64;
        }
        return;
    }
    let step = total / (n - 1) as f64;
    let mut i = 0;
    for (j, o) in out.iter_mut().enumerate() {
        let target = j as f64 * step;
        while i < n - 2 && u[i + 1] < target {
            i += 1;
        }
        let seg = u[i + 1] - u[i];
        let f = if seg > 0.0 {
            ((target - u[i]) / seg).clamp(0.0, 1.0)
        } else {
            0.0
        };
        *o = i as f64 + f;
    }
    out[0] = 0.0;
    out[n - 1] = (n - 1) as f64;
}

/// `values` linearly interpolated at fractional index `a`.
fn lerp_at(values: &[f32], a: f64) -> f32 {
    let i = (a.floor() as usize).min(values.len() - 2);
    let f = (a - i as f64) as f32;
    values[i] + (values[i + 1] - values[i]) * f
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

/// Whether cell (s, t) of Φ turns left at all four corners (counter-clockwise and convex).
pub fn cell_convex(phi: &[[f32; 2]], n: usize, s: usize, t: usize) -> bool {
    let p = [
        phi[t * n + s],
        phi[t * n + s + 1],
        phi[(t + 1) * n + s + 1],
        phi[(t + 1) * n + s],
    ];
    (0..4).all(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % 4], p[(k + 2) % 4]);
        let cross = (b[0] - a[0]) as f64 * (c[1] - b[1]) as f64
            - (b[1] - a[1]) as f64 * (c[0] - b[0]) as f64;
        cross > 0.0
    })
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

    fn mapping(imp: &[f32]) -> Vec<f64> {
        let mut u = vec![0.0; imp.len()];
        let mut out = vec![0.0; imp.len()];
        line_mapping(|i| imp[i], &mut u, &mut out);
        out
    }

    #[test]
    fn uniform_importance_is_the_identity() {
        let m = mapping(&[3.0; 9]);
        assert!(
            m.iter()
                .enumerate()
                .all(|(j, &a)| (a - j as f64).abs() < 1e-12)
        );
    }

    #[test]
    fn a_heavy_segment_takes_its_share_of_outputs() {
        // Weights 1, 1, 7 (the last segment's average is (1+13)/2=7): it gets 7/9 of 4 outputs.
        let m = mapping(&[1.0, 1.0, 1.0, 13.0]);
        // u = [0, 1, 2, 9]; output j sits at u = j·3.
        assert!((m[1] - 2.0 - 1.0 / 7.0).abs() < 1e-12, "{m:?}");
        assert!((m[2] - 2.0 - 4.0 / 7.0).abs() < 1e-12, "{m:?}");
        assert_eq!((m[0], m[3]), (0.0, 3.0));
    }

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
