//! The warp's sample budget: the mesh a frame's importance asks for, so that a smaller image, a
//! larger `quad_px` or a view with less in it draws fewer triangles, and `warp.mesh` is only the
//! upper bound (`docs/design.md`, The warp: the warp's sample budget may follow from the demanded
//! density).
//!
//! Rules:
//! - Importance I is samples per metre per axis, so a sketch-map texel of side d0 asks for
//!   (I·d0)² cells; the frame asks for `cells = Σ (I·d0)²` over the map — the normalisation of the
//!   density ratio with k = 1 — and a mesh of `m = ⌈√cells⌉ + 1` vertices a side.
//! - m is taken up to the next rung of a ladder from `warp.min_mesh` to `warp.mesh`, each rung
//!   about 2^(1/4) above the one before and a multiple of 8 (the passes' 8×8 workgroups), so the
//!   mesh changes by whole steps rather than every frame.
//! - Hysteresis: a frame steps down a rung only when its demand fits 90 % of the lower rung, so a
//!   demand hovering at a rung's edge does not switch the mesh (and resample every vertex) back
//!   and forth between frames. A snapshot must not depend on the frames before it: `batch`, which
//!   keeps one renderer across unrelated cameras, calls [`Budget::forget`] (through
//!   `Renderer::forget`) before each.
//!
//! Rejected alternative: every mesh size from min to max. Each change of m moves every vertex of
//! the zoomed geometry image, which shows as swimming; rungs a fourth of an octave apart cost at
//! most 19 % more cells than asked for.

/// The ladder and the rung the last frame drew.
#[derive(Clone, Debug)]
pub struct Budget {
    rungs: Vec<u32>,
    current: Option<usize>,
    /// Cells the last frame's importance asked for.
    pub demanded_cells: f64,
}

impl Budget {
    /// Rungs from `min` to `max` vertices a side (`max` always a rung, `min` raised to 2).
    pub fn new(min: u32, max: u32) -> Budget {
        let max = max.max(2);
        let mut rungs = vec![min.clamp(2, max)];
        loop {
            let last = *rungs.last().expect("one rung");
            let next = ((last as f64 * 2f64.powf(0.25) / 8.0).ceil() * 8.0) as u32;
            if next >= max {
                break;
            }
            rungs.push(next.max(last + 1));
        }
        if *rungs.last().expect("one rung") < max {
            rungs.push(max);
        }
        Budget {
            rungs,
            current: None,
            demanded_cells: 0.0,
        }
    }

    /// The next frame chooses its rung afresh, without hysteresis.
    pub fn forget(&mut self) {
        self.current = None;
    }

    /// The mesh sides a frame may choose among, vertices, ascending from `warp.min_mesh` to
    /// `warp.mesh`.
    pub fn rungs(&self) -> &[u32] {
        &self.rungs
    }

    /// The mesh for a frame whose importance (per metre, on a map of spacing `d0`) is `importance`.
    pub fn update(&mut self, importance: &[f32], d0: f64) -> u32 {
        let cells = cells_demanded(importance, d0);
        self.demanded_cells = if cells.is_finite() { cells } else { 0.0 };
        let demand = self.demanded_cells.sqrt().ceil() + 1.0;
        let fits = |k: usize| self.rungs[k] as f64 >= demand;
        let wanted = (0..self.rungs.len())
            .find(|&k| fits(k))
            .unwrap_or(self.rungs.len() - 1);
        let k = match self.current {
            Some(c) if wanted < c && demand > 0.9 * self.rungs[c - 1] as f64 => c,
            _ => wanted,
        };
        self.current = Some(k);
        self.rungs[k]
    }
}

/// `Σ (I·d0)²`, summed in eight lanes: one running f64 sum is a chain of dependent additions.
/// Built for AVX-512 where the processor has it, the eight lanes one register; the same lanes in
/// the same order, so the same bits.
pub fn cells_demanded(importance: &[f32], d0: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() {
        // SAFETY: the processor has AVX-512F and AVX2 (`simd::avx512`), checked just above.
        return unsafe { cells_demanded_avx512(importance, d0) };
    }
    cells_in_lanes(importance, d0)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2")]
unsafe fn cells_demanded_avx512(importance: &[f32], d0: f64) -> f64 {
    cells_in_lanes(importance, d0)
}

#[inline(always)]
fn cells_in_lanes(importance: &[f32], d0: f64) -> f64 {
    const LANES: usize = 8;
    let mut sums = [0f64; LANES];
    let chunks = importance.chunks_exact(LANES);
    let rest: f64 = chunks
        .remainder()
        .iter()
        .map(|&i| (i as f64 * d0).powi(2))
        .sum();
    for c in chunks {
        for (s, &i) in sums.iter_mut().zip(c) {
            *s += (i as f64 * d0).powi(2);
        }
    }
    sums.iter().sum::<f64>() + rest
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rungs_climb_by_a_quarter_octave_in_multiples_of_eight_to_the_bound() {
        let b = Budget::new(32, 512);
        let r = b.rungs();
        assert_eq!((r[0], *r.last().unwrap()), (32, 512));
        for w in r.windows(2) {
            let ratio = w[1] as f64 / w[0] as f64;
            assert!(ratio > 1.0 && ratio < 1.5, "{r:?}");
        }
        assert!(r[1..r.len() - 1].iter().all(|m| m % 8 == 0), "{r:?}");
        assert_eq!(Budget::new(600, 512).rungs(), [512]);
    }

    #[test]
    fn the_mesh_covers_the_demand_and_steps_down_only_clearly() {
        let mut b = Budget::new(16, 1024);
        // 100 texels of d0 = 2 m at 5 samples per metre: (5·2)² · 100 = 10,000 cells, m ≥ 101.
        let m = b.update(&[5.0; 100], 2.0);
        assert_eq!(b.demanded_cells, 10_000.0);
        assert!(m >= 101 && (m as f64) < 101.0 * 1.25, "{m}");
        // A demand just under the lower rung keeps the mesh; well under it, the mesh steps down.
        let below = b.rungs()[b.rungs().iter().position(|&r| r == m).unwrap() - 1] as f64;
        let at = |mesh: f64| ((mesh - 1.0).powi(2) / 100.0).sqrt() / 2.0;
        assert_eq!(b.update(&[at(below * 0.95) as f32; 100], 2.0), m);
        // Forgotten, the same demand gets the rung a fresh budget gives it.
        let mut fresh = Budget::new(16, 1024);
        let alone = fresh.update(&[at(below * 0.95) as f32; 100], 2.0);
        assert!(alone < m);
        b.forget();
        assert_eq!(b.update(&[at(below * 0.95) as f32; 100], 2.0), alone);
        b.update(&[5.0; 100], 2.0);
        assert!(b.update(&[at(below * 0.8) as f32; 100], 2.0) < m);
        // Nothing asked: the floor; NaN never passes.
        assert_eq!(b.update(&[0.0; 100], 2.0), 16);
        assert_eq!(b.update(&[f32::NAN; 100], 2.0), 16);
        assert_eq!(b.update(&[1e9; 100], 2.0), 1024);
    }
}
