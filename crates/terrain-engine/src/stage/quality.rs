//! Quality figures of one warp (`docs/design.md`, Density ratio): the density ratio over visible
//! cells, flipped cells and non-finite values.
//!
//! For cell (s, t): obtained density `ρ_o = 1/sqrt(|Φ_s|·|Φ_t|)`, each side length the mean of the
//! cell's two edges along that direction; demanded `ρ_d = k·I(centre)`, I sampled bilinearly from the
//! importance map, with `k` fixing the total demand to the `(n−1)²` cells there are. A cell is
//! visible when `S_f ≥ 0.5` at its centre; it is flipped when its signed area is ≤ 0.
//!
//! `demand_met` weighs the ratio's shares: counted by cells, a spread of ratios leans above 1
//! even when the view gets exactly its demand (a cell of ratio r stands for 1/r² demanded cells),
//! so a share within [½, 1] means little without how many cells the view got for its demand.

use crate::stage::budget::cells_demanded;
use crate::stage::importance::ImportanceMap;
use crate::stage::warp::cell_area;
use serde::Serialize;

/// Histogram bin edges in log2(ratio): 1/8 … 8 in half-octave steps, plus the two open ends.
pub(crate) const BIN_EDGES_LOG2: [f64; 13] = [
    -3.0, -2.5, -2.0, -1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0,
];

/// One bin of the density ratio's histogram: half an octave wide, the ends open.
#[derive(Clone, Debug, Serialize)]
pub struct Bin {
    /// Ratio range [lo, hi) of the bin; 0 and infinity at the open ends.
    pub lo: f64,
    /// The bin's upper edge (exclusive); infinity for the last bin.
    pub hi: f64,
    /// Visible cells whose ratio falls in the bin.
    pub cells: usize,
}

/// How well one warp met its importance: the density ratio (obtained ÷ demanded sample density)
/// over the visible cells, and the cells that fold or are not finite. `warp` and
/// `render --json` report it.
#[derive(Clone, Debug, Serialize)]
pub struct Quality {
    /// Cells whose centre lies in view (`S_f ≥ 0.5`) and whose ratio is finite.
    pub cells_visible: usize,
    /// Share of the visible cells whose ratio lies in [½, 2], 0 to 1.
    pub ratio_within_0_5_2: f64,
    /// Share of the visible cells whose ratio lies in [½, 1], 0 to 1.
    pub ratio_within_0_5_1: f64,
    /// The median ratio over the visible cells (NaN where none is).
    pub ratio_median: f64,
    /// The visible cells over the cells their importance demands (`Σ 1/r²` over them): 1 when
    /// the view gets as many cells as it asks for, less when cells went where nothing shows.
    pub demand_met: f64,
    /// Cells of Φ, visible or not, whose signed area is ≤ 0 (folded).
    pub flipped_cells: usize,
    /// Non-finite values met: in Φ, in the importance map, and visible cells' ratios.
    pub nonfinite: usize,
    /// The visible cells' ratios by half-octave bins from ⅛ to 8, the ends open.
    pub histogram: Vec<Bin>,
}

/// Measures Φ (region-local metres, spacing `d0` between sketch map texels) against the importance
/// it was made from. `ratios` receives each cell's ratio (NaN for cells not visible).
pub fn measure(
    phi: &[[f32; 2]],
    n: usize,
    d0: f64,
    imp: &ImportanceMap,
    ratios: &mut Vec<f32>,
) -> Quality {
    // k scales the demand, Σ (I·d0)² cells (the budget's), to the (n − 1)² cells there are.
    let k = (n - 1) as f64 / cells_demanded(&imp.importance, d0).sqrt();
    let len = |a: [f32; 2], b: [f32; 2]| ((b[0] - a[0]) as f64).hypot((b[1] - a[1]) as f64);
    let mut nonfinite = phi
        .iter()
        .filter(|p| !(p[0].is_finite() && p[1].is_finite()))
        .count()
        + imp.importance.iter().filter(|v| !v.is_finite()).count()
        + imp.nonfinite;
    let mut flipped = 0;
    ratios.clear();
    let mut visible: Vec<f32> = Vec::new();
    for t in 0..n - 1 {
        for s in 0..n - 1 {
            let at = |a: usize, b: usize| phi[b * n + a];
            if cell_area(phi, n, s, t) <= 0.0 {
                flipped += 1;
            }
            let (p00, p10, p01, p11) = (at(s, t), at(s + 1, t), at(s, t + 1), at(s + 1, t + 1));
            let ds = 0.5 * (len(p00, p10) + len(p01, p11));
            let dt = 0.5 * (len(p00, p01) + len(p10, p11));
            let cx = 0.25 * (p00[0] + p10[0] + p01[0] + p11[0]) / d0 as f32;
            let cy = 0.25 * (p00[1] + p10[1] + p01[1] + p11[1]) / d0 as f32;
            let rho_o = 1.0 / (ds * dt).sqrt();
            let rho_d = k * imp.sample(&imp.importance, cx, cy) as f64;
            let r = (rho_o / rho_d) as f32;
            if imp.sample(&imp.frustum, cx, cy) >= 0.5 {
                if r.is_finite() {
                    visible.push(r);
                } else {
                    nonfinite += 1;
                }
                ratios.push(r);
            } else {
                ratios.push(f32::NAN);
            }
        }
    }
    summarise(visible, flipped, nonfinite)
}

fn summarise(mut visible: Vec<f32>, flipped_cells: usize, nonfinite: usize) -> Quality {
    let count = visible.len();
    // A cell of ratio r stands where its importance asks for 1/r² cells (ρ_d² over ρ_o²).
    let demanded: f64 = visible.iter().map(|&r| (r as f64).powi(-2)).sum();
    let demand_met = if count == 0 {
        1.0
    } else {
        count as f64 / demanded
    };
    let frac = |lo: f32, hi: f32| {
        if count == 0 {
            return 1.0;
        }
        visible.iter().filter(|&&r| r >= lo && r <= hi).count() as f64 / count as f64
    };
    let within_0_5_2 = frac(0.5, 2.0);
    let within_0_5_1 = frac(0.5, 1.0);
    let mut histogram: Vec<Bin> = (0..=BIN_EDGES_LOG2.len())
        .map(|b| Bin {
            lo: if b == 0 {
                0.0
            } else {
                BIN_EDGES_LOG2[b - 1].exp2()
            },
            hi: BIN_EDGES_LOG2.get(b).map_or(f64::INFINITY, |e| e.exp2()),
            cells: 0,
        })
        .collect();
    for &r in &visible {
        let l = (r as f64).log2();
        let b = BIN_EDGES_LOG2.iter().take_while(|&&e| l >= e).count();
        histogram[b].cells += 1;
    }
    visible.sort_by(f32::total_cmp);
    let ratio_median = visible.get(count / 2).map_or(f64::NAN, |&r| r as f64);
    Quality {
        cells_visible: count,
        ratio_within_0_5_2: within_0_5_2,
        ratio_within_0_5_1: within_0_5_1,
        ratio_median,
        demand_met,
        flipped_cells,
        nonfinite,
        histogram,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demand_met_counts_what_each_cell_stands_for() {
        // A cell of ratio 1 stands for one demanded cell, one of ratio 2 for a quarter: two
        // cells where 1.25 are asked for. (The mean of r² would say 2.5; of r, 1.5.)
        let q = summarise(vec![1.0, 2.0], 0, 0);
        assert!(
            (q.demand_met - 2.0 / 1.25).abs() < 1e-12,
            "{}",
            q.demand_met
        );
        assert_eq!(summarise(Vec::new(), 0, 0).demand_met, 1.0);
    }
}
