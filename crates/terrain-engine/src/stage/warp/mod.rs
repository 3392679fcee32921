//! The warp: a row pass then a column pass over the sketch map's geometry image, moving its samples
//! so that each segment gets output room in proportion to its importance (`docs/design.md`, The
//! warp).
//!
//! Rules:
//! - One line's warp is a *mapping* (`stage::lines`): the fractional source index of each output
//!   sample, monotone, 0 and n−1 at the ends.
//! - The row pass warps x along each row and resamples importance the same way; the column pass
//!   warps each column of the row-warped image by that resampled importance. Both map eight
//!   lines at a time (`lines::lane_mappings`) and interpolate eight at a time
//!   (`lines::lerp_lanes`).
//! - `Plain` stops there: the paper's method. Where neighbouring columns want very different column
//!   warps and the rows under them were warped differently too, cells fold.
//! - `Guarded` (the default) keeps both triangles of every cell counter-clockwise and every row of Φ
//!   increasing in x. A cell split along its diagonal from (s, t) to (s+1, t+1) is then sound;
//!   the GPU splits a convex cell along the other diagonal where that lies nearer the surface
//!   (`lod::warped::mesh_split`), and a merely non-convex cell keeps this one. A flipped triangle is a
//!   fold on screen. The guard gives the columns on either side of a folded cell (and one more
//!   each way) the *mean* column mapping `b̄`, that of the row-warped importance summed across
//!   columns, and repeats until nothing folds. A cell between two columns that both follow `b̄`
//!   is a convex trapezoid between two rows of equal y and cannot fold, so the loop ends; the
//!   other columns keep their own warp (docs/decisions.md, “Guarded warp”).
//! - When more than an eighth of the column pairs fold at the start ([`fallback_pairs`]: 16 of
//!   127; near views), all columns go to `b̄` at once: the rounds would end there, or nearly
//!   there, anyway (docs/decisions.md, “Fold fallback at an eighth”). The columns are mapped,
//!   passed and checked eight at a time, so that this is decided as soon as it is certain. No
//!   exact test decides it sooner (a fold is known only from Φ), and a guess would change the
//!   warp wherever it guessed wrong.
//! - Where the near views fold: along the frustum's side edges, where the row warp crowds the
//!   columns outside the view into slivers a fraction of a metre wide that lean with the edge, and
//!   in the rows behind the camera, where the region's fixed bottom edge holds the row warp's
//!   crowded samples. A sliver folds at any difference between its two columns' mappings, so
//!   only the same mapping on both sides repairs it.
//! - Orientation: the second pass is the one the guard may send to a single mean mapping, and a
//!   mean mapping serves only a pass along the view's depth, whose demand (falling with distance)
//!   is alike in every line; across the depth the frustum's edges move from line to line. So
//!   where the view's depth runs along x, the warp runs across ([`Warp::run_across`]): columns
//!   first, then rows, on the map transposed, Φ transposed back (docs/decisions.md, “Warp across
//!   the view's depth”). The heading decides, and turns the warp only past the diagonal by 25 %
//!   (`stage::TURN_RATIO`), so that a heading near 45° does not flip the mesh from frame to
//!   frame. Neither order serves a heading near a diagonal: there the stage turns the sketch
//!   map's region by 45° instead (`stage::sketch_map::Turn`, chosen by `stage::heading_of`), and
//!   this warp runs rows first over it, unchanged; Φ lies along the region's axes. A region turned
//!   to the exact heading is not built: its lattice would turn with the camera, and the sketch map
//!   would swim.
//! - An optional limit on the importance gradient (`max_log2_step`) raises low importance next to
//!   high, in log space, before warping: fewer folds to guard, at the cost of spreading cells.
//! - All buffers are allocated once in [`Warp::new`], the two the warp across needs on the first
//!   frame that runs across; a frame allocates nothing after.
//! - One thread: a frame's warp is too short a piece of work to hand part of it to another
//!   thread (docs/decisions.md, “One thread for the CPU stage”).
//!
//! Speed (docs/decisions.md, “Warp in lanes of eight”):
//! - `run` is built for AVX-512 and AVX2 and chosen at run time: otherwise the calls into the AVX2
//!   kernels are not inlined.
//! - With AVX-512F, the row pass's and the column pass's loops over a group of eight whole lines
//!   are one kernel each (`lines::row_samples`, `lines::column_points`): built from the lanes'
//!   generic code, every sample also paid the run-time choice of build, bounds checks and copies
//!   through the stack, more instructions than the gather it waits on. A partial last group and
//!   the AVX2 build keep the generic loops, with the same bits.
//! - The all-mean pass interpolates columns put side by side instead of gathering them, and the
//!   importance is read in place unless `max_log2_step` limits it (then a copy a frame).
//! - The fold check takes eight column pairs at once (in AVX-512F where the processor has it,
//!   `x86::pairs_unfolded`) and stops at the first block of 16 rows after which all eight have
//!   folded. The first group's seven pairs wait for the second group, so that they too are
//!   checked eight at once; the count only decides when the shortcut is taken, and it grows the
//!   same.
//! - The mean column mapping is made only where a fold needs it.
//! - Stores of a group's last, partial lanes: `store_kept_apart` (a cold call) in the all-mean
//!   pass and `store_columns`, where LLVM would otherwise merge both branches into a memcpy call
//!   for every group; `store_kept` (inlined) in the row pass, whose f32 stores it serves better.
//!
//! Rejected alternatives:
//! - Moving columns toward `b̄` by halves (λ = ½, ¼, …): twice the instructions for the same share
//!   of cells within [½, 2] (docs/decisions.md, “Guarded warp”).
//! - Local repairs in place of the all-columns fallback (relaxing or blending the column mappings
//!   toward the mean, untangling Φ, limiting the importance gradient outside the frustum, a power
//!   mean for `b̄`): none kept a near view off the fallback (docs/decisions.md, “Guarded warp”).
//! - Extra row/column passes over the warped image: the grid is no longer axis-aligned, and a
//!   second pass can fold what the first left intact.
//! - Always smoothing the importance: it lowers the density ratio everywhere to fix folds that
//!   occur in a few places.
//! - Other arrangements of the lanes (an 8×8 transpose in registers for `side_by_side`, two groups
//!   of rows at a time in the row pass, the row pass's importance gathered from lines side by side
//!   or carried through the mapping kernel, the guard's rounds checking pairs eight at once,
//!   buffers on 64-byte boundaries): none faster (docs/decisions.md, “Warp in lanes of eight”).

mod fold;
mod passes;

pub use fold::{cell_area, pair_unfolded, pairs_unfolded};

use crate::scene::WarpMethod;
use crate::stage::lines::{LANES, LaneScratch, LineScratch};
use crate::stage::transpose;

/// The row and column warp (Dachsbacher & Stamminger 2004): moves the n × n sketch map's
/// grid so samples are spaced inversely to the importance, giving Φ. Holds every buffer it
/// needs, sized once for n.
pub struct Warp {
    n: usize,
    /// How folds are kept away: the paper's passes alone, or guarded (`warp.method`).
    pub method: WarpMethod,
    /// Largest log2 step of importance between 4-neighbours; 0: no limit.
    pub max_log2_step: f32,
    /// The importance after `max_log2_step`'s limit: empty without one, sized in `new` or on the
    /// first frame that limits (if the limit is set after `new`).
    limited: Vec<f32>,
    scratch: LineScratch,
    lanes: LaneScratch,
    lanes_in: Vec<[f32; LANES]>,
    lanes_out: Vec<[f64; LANES]>,
    // The row pass's output, transposed (column s at [s·n ..]) so the column pass reads lines.
    row_x: Vec<f32>,
    row_importance: Vec<f32>,
    mean_importance: Vec<f32>,
    mean_map: Vec<f64>,
    /// Columns the guard sent to the mean column warp.
    follows_mean: Vec<bool>,
    changed: Vec<bool>,
    folded: Vec<bool>,
    /// Φ: output (s, t) → region-local (x, y) metres, row-major with t the row.
    pub phi: Vec<[f32; 2]>,
    /// Columns the guard sent to the mean column warp in the last frame (lines of x, not y,
    /// where the last frame ran [`Warp::run_across`]).
    pub guarded_columns: usize,
    /// The importance transposed, and Φ before it is transposed back, for [`Warp::run_across`]:
    /// empty until the first frame that runs across (a view that never looks east or west does
    /// not hold them; at `warp.size` 4096 they take 200 MB).
    transposed: Vec<f32>,
    phi_across: Vec<[f32; 2]>,
    /// Whether the last frame ran [`Warp::run_across`].
    pub across: bool,
    /// Folded column pairs at which the guard sends every column to the mean at once
    /// (`fallback_pairs` of n); `usize::MAX`: only the guard's rounds.
    pub fallback_pairs: usize,
}

/// The folded column pairs, of n − 1, at which every column goes to the mean column warp at once:
/// more than an eighth (16 of 127 at n = 128). From there the guard's rounds end with all or
/// nearly all columns on the mean anyway (the module doc's census, at n = 128), so searching
/// further is wasted.
pub fn fallback_pairs(n: usize) -> usize {
    (n.max(2) - 1) / 8 + 1
}

impl Warp {
    /// A warp of an n × n grid by `method`, the importance limited to `max_log2_step` octaves
    /// between neighbours (0: no limit).
    pub fn new(n: usize, method: WarpMethod, max_log2_step: f32) -> Warp {
        Warp {
            n,
            method,
            max_log2_step,
            limited: if max_log2_step > 0.0 {
                vec![0.0; n * n]
            } else {
                Vec::new()
            },
            scratch: LineScratch::new(n),
            lanes: LaneScratch::new(n),
            lanes_in: vec![[0.0; LANES]; n],
            lanes_out: vec![[0.0; LANES]; n],
            row_x: vec![0.0; n * n],
            row_importance: vec![0.0; n * n],
            mean_importance: vec![0.0; n],
            mean_map: vec![0.0; n],
            follows_mean: vec![false; n],
            changed: vec![false; n],
            folded: vec![false; n],
            phi: vec![[0.0; 2]; n * n],
            guarded_columns: 0,
            transposed: Vec::new(),
            phi_across: Vec::new(),
            across: false,
            fallback_pairs: fallback_pairs(n),
        }
    }

    /// The grid's side, texels (`warp.size`).
    pub fn n(&self) -> usize {
        self.n
    }

    /// Warps the n² grid of spacing `d0` (region-local: texel (i, j) at (i·d0, j·d0)) by
    /// `importance` (n², row-major). The result is in [`Warp::phi`].
    pub fn run(&mut self, importance: &[f32], d0: f32) {
        self.across = false;
        self.run_rows_first(importance, d0);
    }

    /// [`Warp::run`] with the passes' roles swapped: columns first, then rows, which the guard
    /// may send to the mean row mapping. For a view whose depth runs along x (the module doc's
    /// rule on orientation). It warps the map transposed and transposes Φ back, so Φ is the
    /// same grid as [`Warp::run`]'s: (s, t) → (x, y). Each of the two reflections (of the output
    /// grid, of the region) reverses a cell's turn, so together they keep it: a warp that folds
    /// nowhere stays so.
    pub fn run_across(&mut self, importance: &[f32], d0: f32) {
        let n = self.n;
        assert_eq!(importance.len(), n * n, "importance map size");
        let mut transposed = std::mem::take(&mut self.transposed);
        transposed.resize(n * n, 0.0);
        self.phi_across.resize(n * n, [0.0; 2]);
        transpose::importance(importance, &mut transposed, n);
        self.run_rows_first(&transposed, d0);
        self.transposed = transposed;
        std::mem::swap(&mut self.phi, &mut self.phi_across);
        transpose::phi(&self.phi_across, &mut self.phi, n);
        self.across = true;
    }

    fn run_rows_first(&mut self, importance: &[f32], d0: f32) {
        #[cfg(target_arch = "x86_64")]
        {
            if crate::stage::simd::avx512() {
                // SAFETY: the processor has AVX-512F and AVX2 (`simd::avx512`), checked just above.
                return unsafe { self.run_avx512(importance, d0) };
            }
            if crate::stage::simd::avx2() {
                // SAFETY: the processor has AVX2, checked just above.
                return unsafe { self.run_avx2(importance, d0) };
            }
        }
        self.run_lanes(importance, d0)
    }

    /// [`Warp::run`] compiled for AVX-512's eight f64 lanes, one [`LANES`] group to a register.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2")]
    unsafe fn run_avx512(&mut self, importance: &[f32], d0: f32) {
        self.run_lanes(importance, d0)
    }

    /// [`Warp::run`] compiled for AVX2's four f64 lanes.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn run_avx2(&mut self, importance: &[f32], d0: f32) {
        self.run_lanes(importance, d0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stage::lines::lerp_at;
    use crate::stage::lines::tests::{mapping, uniform};
    /// Importance over twelve orders of magnitude, from a seed.
    pub(super) fn random_map(n: usize, seed: u32) -> Vec<f32> {
        let mut rnd = uniform(seed);
        (0..n * n).map(|_| 10f32.powf(12.0 * rnd() - 6.0)).collect()
    }

    /// The warp as it was written before lanes (99bf083): one line at a time, columns mapped,
    /// passed and checked one by one. Returns Φ and the columns on the mean.
    fn one_line_at_a_time(imp: &[f32], n: usize, d0: f32, guarded: bool) -> (Vec<[f32; 2]>, usize) {
        let (mut row_x, mut row_imp) = (vec![0.0f32; n * n], vec![0.0f32; n * n]);
        for t in 0..n {
            let row = &imp[t * n..(t + 1) * n];
            for (s, &a) in mapping(row).iter().enumerate() {
                row_x[s * n + t] = (a * d0 as f64) as f32;
                row_imp[s * n + t] = lerp_at(row, a);
            }
        }
        let mut mean = vec![0.0f32; n];
        for s in 0..n {
            for (m, &v) in mean.iter_mut().zip(&row_imp[s * n..(s + 1) * n]) {
                *m += v;
            }
        }
        let mean_map = mapping(&mean);
        let maps: Vec<Vec<f64>> = (0..n)
            .map(|s| mapping(&row_imp[s * n..(s + 1) * n]))
            .collect();
        let mut phi = vec![[0.0f32; 2]; n * n];
        let mut on_mean = vec![false; n];
        let pass = |phi: &mut Vec<[f32; 2]>, s: usize, map: &[f64]| {
            for (t, &b) in map.iter().enumerate() {
                phi[t * n + s] = [
                    lerp_at(&row_x[s * n..(s + 1) * n], b),
                    (b * d0 as f64) as f32,
                ];
            }
        };
        let mut folded = vec![false; n];
        let mut count = 0;
        for s in 0..n {
            pass(&mut phi, s, &maps[s]);
            if guarded && s > 0 {
                folded[s - 1] = !pair_unfolded(&phi, n, s - 1);
                count += usize::from(folded[s - 1]);
                if count >= fallback_pairs(n) {
                    (0..n).for_each(|s| pass(&mut phi, s, &mean_map));
                    return (phi, n);
                }
            }
        }
        if !guarded {
            return (phi, 0);
        }
        loop {
            let mut changed = vec![false; n];
            for s in (0..n - 1).filter(|&s| folded[s]) {
                for c in s.saturating_sub(1)..=(s + 2).min(n - 1) {
                    changed[c] = !on_mean[c];
                }
            }
            if !changed.contains(&true) {
                break;
            }
            for s in (0..n).filter(|&s| changed[s]) {
                on_mean[s] = true;
                pass(&mut phi, s, &mean_map);
            }
            for s in (0..n - 1).filter(|&s| changed[s] || changed[s + 1]) {
                folded[s] = !pair_unfolded(&phi, n, s);
            }
        }
        (phi, on_mean.iter().filter(|&&m| m).count())
    }

    #[test]
    fn lanes_warp_exactly_as_one_line_at_a_time() {
        // Each map takes one path of the guarded warp: random importance folds most pairs (all
        // columns to the mean at once), a bump on a slope folds a few (guard rounds), importance
        // that is a product of a row and a column profile never folds.
        let bump = |n: usize| -> Vec<f32> {
            // Tuned by trial to fold a few pairs, under the shortcut's threshold (4 of 36, 10 of
            // 127), so that the rounds run: they end with 28 of 37 and 78 of 128 columns on the
            // mean.
            let width = if n < 64 { 0.001 } else { 0.002 };
            (0..n * n)
                .map(|k| {
                    let (x, y) = ((k % n) as f32 / n as f32, (k / n) as f32 / n as f32);
                    let d2 = (x - 0.4).powi(2) + (y - 0.6).powi(2);
                    1.0 + 3.0 * y + 25.0 * (-d2 / width).exp()
                })
                .collect()
        };
        let product = |n: usize| -> Vec<f32> {
            (0..n * n)
                .map(|k| (1.0 + (k % n) as f32).sqrt() * (2.0 + ((k / n) as f32 * 0.3).sin()))
                .collect()
        };
        // 37 leaves a lane group part-filled at the end of both passes.
        for n in [37, 128] {
            for (name, imp, on_mean) in [
                ("random", random_map(n, 7), Some(n)),
                ("bump", bump(n), None),
                ("product", product(n), Some(0)),
            ] {
                for method in [WarpMethod::Plain, WarpMethod::Guarded] {
                    let guarded = method == WarpMethod::Guarded;
                    let (want, want_on_mean) = one_line_at_a_time(&imp, n, 2.5, guarded);
                    let mut warp = Warp::new(n, method, 0.0);
                    warp.run(&imp, 2.5);
                    for (k, (got, want)) in warp.phi.iter().zip(&want).enumerate() {
                        let (got, want) = (got.map(f32::to_bits), want.map(f32::to_bits));
                        assert_eq!(got, want, "{name} n {n} {method:?} vertex {k}");
                    }
                    if guarded {
                        assert_eq!(warp.guarded_columns, want_on_mean, "{name} n {n}");
                        match on_mean {
                            Some(m) => assert_eq!(want_on_mean, m, "{name} n {n}"),
                            None => assert!(
                                want_on_mean > 0 && want_on_mean < n,
                                "{name} n {n}: {want_on_mean} columns on the mean"
                            ),
                        }
                    }
                }
            }
        }
    }

    /// The shortcut's threshold: more than an eighth of the n − 1 column pairs, and the least
    /// such count.
    #[test]
    fn the_shortcut_takes_more_than_an_eighth_of_the_pairs() {
        for (n, pairs) in [(128, 16), (129, 17), (9, 2), (8, 1), (2, 1), (37, 5)] {
            assert_eq!(fallback_pairs(n), pairs, "n {n}");
            assert!(8 * pairs > n - 1 && 8 * (pairs - 1) < n, "n {n}");
        }
    }
}
