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
//!   (`gpu::mesh_split`), and a merely non-convex cell keeps this one. A flipped triangle is a
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

use crate::scene::WarpMethod;
use crate::stage::lines::{
    LANES, LaneLines, LaneScratch, LineScratch, lane_mappings, lerp_at, lerp_lanes, lerp_weight,
    line_mapping,
};
use crate::stage::transpose;

pub struct Warp {
    n: usize,
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
    /// ([`fallback_pairs`] of n); `usize::MAX`: only the guard's rounds.
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

    #[inline(always)]
    fn run_lanes(&mut self, importance: &[f32], d0: f32) {
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

    /// Records whether the columns `pair`, `pair + 1` fold and counts it; true once the count
    /// reaches `fallback_pairs`. The order in which pairs are counted changes only when the
    /// count is reached, never whether it is.
    #[inline(always)]
    fn tally_pair(&mut self, pair: usize, unfolded: bool, folded: &mut usize) -> bool {
        self.folded[pair] = !unfolded;
        *folded += usize::from(!unfolded);
        *folded >= self.fallback_pairs
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
        store_columns(&mut self.phi, &self.row_x, n, s0, d0, |t| maps[t]);
    }

    /// Column s of Φ from the mean column mapping (the guard's).
    #[inline(always)]
    fn column_pass(&mut self, s: usize, d0: f32) {
        let n = self.n;
        let xs = &self.row_x[s * n..][..n];
        for (t, &b) in self.mean_map.iter().enumerate() {
            self.phi[t * n + s] = [lerp_at(xs, b), (b * d0 as f64) as f32];
        }
    }

    /// Sends the columns beside every folded cell (`folded`, set by the column pass) to the mean
    /// column warp, until no triangle of the mesh is flipped. Each round moves at least one more
    /// column, so it ends.
    #[inline(always)]
    fn guard(&mut self, d0: f32) {
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

/// Whether every cell between columns s and s+1 of Φ is sound (see [`cell_turn`]).
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
/// (interleaved points leave the lane loop to shuffles). The same operations in the same order,
/// `f32::min`'s choice of the number over NaN included: the same results. Rejected: the check
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
        // f32::min: the number where one operand is NaN.
        let min = |a: __m256, b: __m256| {
            let m = _mm256_min_ps(a, b);
            _mm256_blendv_ps(m, a, _mm256_cmp_ps::<_CMP_UNORD_Q>(b, b))
        };
        let zero = _mm256_setzero_ps();
        let mut least = _mm256_set1_ps(f32::INFINITY);
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
                let t_min = min(
                    min(min(abc, cda), _mm256_sub_ps(bx, ax)),
                    _mm256_sub_ps(cx, dx),
                );
                // `if turn < least { least = turn }`: min_ps keeps its second operand on NaN.
                least = _mm256_min_ps(t_min, least);
                lo = hi;
            }
            if _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(least, zero)) == 0 {
                break 'blocks;
            }
        }
        let sound = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(least, zero));
        std::array::from_fn(|l| sound & (1 << l) != 0)
    }
}

/// Positive when cell (s, t) is sound: neither of its two triangles (split along the diagonal
/// from (s, t) to (s+1, t+1), as the mesh is drawn unless the cell is convex: `gpu::mesh_split`)
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
    use crate::stage::lines::tests::{mapping, uniform};

    /// Importance over twelve orders of magnitude, from a seed.
    fn random_map(n: usize, seed: u32) -> Vec<f32> {
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

    /// The shortcut's threshold: more than an eighth of the n − 1 column pairs, and the least
    /// such count.
    #[test]
    fn the_shortcut_takes_more_than_an_eighth_of_the_pairs() {
        for (n, pairs) in [(128, 16), (129, 17), (9, 2), (8, 1), (2, 1), (37, 5)] {
            assert_eq!(fallback_pairs(n), pairs, "n {n}");
            assert!(8 * pairs > n - 1 && 8 * (pairs - 1) < n, "n {n}");
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
