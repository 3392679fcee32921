//! The importance map: samples per metre wanted at each sketch map texel,
//! `I = max(min(I_v·S_f·S_b, I_s), I_floor)` as `docs/design.md` defines it (Importance).
//!
//! Rules:
//! - `I_v = f_px / (C·d)`, with d clamped below by half the sketch map spacing: the warp is
//!   piecewise linear between texels and cannot deliver a demand that varies inside one.
//! - `S_f` is the product over the frustum's five planes of a smoothstep from 0 at `margin` metres
//!   outside to 1 on the plane; the margin covers a texel's reach (1.5·d0), the detail's
//!   displacement and 2 % of the distance (`MARGIN_SHARE`).
//!   Texels outside the atlas have `S_f = 0`: there is no terrain there to see.
//! - `S_b` is 1 for front-facing and silhouette texels (n·v ≥ −0.05) and falls smoothly to
//!   `backface_floor` at n·v = −0.35.
//! - `I_floor` is `floor` × the least importance of a texel in view, so the invisible rest of the
//!   region keeps a few cells and the warp's weights stay positive. Nothing in view: uniform 1.
//! - With the geometric-error term (`importance.error`, on by default), before S_f, S_b and I_s:
//!   `I = min(I_v, max(I_g, β·I_v))`, `I_g = √(κ·f_px / (8·τ_e·d))` — the sample density at
//!   which linear interpolation misses a surface of curvature κ by τ_e pixels on screen
//!   (`δ = κ s²/8` at spacing s). κ = the sketch map's largest second difference (|h_xx|, |h_yy|,
//!   |h_xy|, one-sided at the map's edges, of the heights raised to the water's level) + the
//!   detail's curvature at spacing `1/I_v`: the octaves that are geometry there (the split
//!   octave with the scene's bias, `docs/design.md`, Procedural detail) weighted by
//!   `0.31·w_k·(2π f_k)²`, 0.31 the noise's RMS; a prefix sum over octaves makes it one log2 per
//!   texel and a sum over the few octaves of its row. Where the sketch map is coarser than the
//!   atlas, + the sketch's curvature the map cannot see at that spacing (`SubTexel`: the
//!   levels' mean curvature at `1/I_v` less at the map's spacing, `Atlas::level_curvature`).
//!   From high up the map's texels are several of the DEM's, whose mean curvature grows at each
//!   finer level: without `SubTexel` the map calls flat the plateaus whose drainage the mesh then
//!   misses (docs/decisions.md, “Geometric-error term”).
//! - Computed in f32 relative to the region's corner, along its axes; world-scale values never
//!   enter the loop. A turned region (`stage::sketch_map::Turn`) has the eye and the frustum's
//!   planes turned into its frame, and each of its rows finds its own texels on the atlas
//!   (`on_atlas`); an axis-aligned region's values are as before, bit for bit.
//!
//! Speed (docs/decisions.md, “Importance map loops”):
//! - Each row loop indexes buffers sliced to the row's length: an index into a buffer of unknown
//!   length is checked, and a checked loop stays scalar. A frustum plane with the whole row
//!   inside is skipped.
//! - The row loops are built for AVX-512 and AVX2 and chosen at run time; the same operations in
//!   the same order, so the same bits. The AVX-512 build has a second copy for maps of the
//!   default side, 128 (`rows::<128>`): with the row's length a constant, each row loop is whole
//!   vectors, without the loop's remainder and its checks.
//! - The error term's octave level is an exponent plus a quintic (`log2_approx`), not the library
//!   call `f32::log2`; the octave prefix is summed over each row's few octaves
//!   (`ErrorTerm::add_curvature_row`); the row's octave range and the last loop's tallies go in
//!   whole chunks of sixteen with plain comparisons; the visible minimum is an integer minimum of
//!   the bits (a conditional f32 store becomes a masked store that the next chunk's load waits
//!   on); the sketch's curvature runs inline, with the row's ends apart, in runs of sixteen with
//!   the last overlapping, its water clamp a plain comparison.
//!
//! Rejected alternatives:
//! - The sketch's curvature as a constant everywhere: it adds to the near views too, where the
//!   map is as fine as the sketch (docs/decisions.md, “Geometric-error term”).
//! - Other shapes of the term (I_g's contrast halved or ¾ of it, the mean-error optimum
//!   `√(I_g·I_v)`, κ's error projected across the ray) and the term off: none matches more
//!   GeoMipMap rows on triangles and error (docs/decisions.md, “Geometric-error term”).
//! - One fused pass over eight texels at a time in `[f32; 8]` arrays (LLVM leaves it scalar);
//!   fewer divisions per texel (the loop is bound by its other arithmetic, and the bits would
//!   change); each row computed only over the texels possibly in view (row lengths that change
//!   from row to row cost each loop's exit prediction); the reductions' lanes folded in halves;
//!   `slope_x` inlined: none faster (docs/decisions.md, “Importance map loops”).
//! - Two threads (docs/decisions.md, “One thread for the CPU stage”).

mod error;
mod rows;
mod view;

pub use error::ErrorTerm;

#[derive(Clone, Debug)]
pub struct ImportanceParams {
    pub quad_px: f64,
    pub view: bool,
    pub frustum: bool,
    pub backface: bool,
    pub max_per_m: Option<f64>,
    pub floor: f64,
    pub backface_floor: f64,
    /// How far procedural detail can displace the surface, metres (widens the frustum margin).
    pub reach_m: f64,
    /// The geometric-error term, when the scene asks for it.
    pub error: Option<ErrorTerm>,
}

#[derive(Clone, Debug)]
pub struct ImportanceMap {
    pub n: usize,
    /// I, samples per metre, row-major like the sketch map.
    pub importance: Vec<f32>,
    /// S_f alone (1 when the frustum factor is off), for deciding which cells are visible.
    pub frustum: Vec<f32>,
    /// Texels whose raw importance was NaN or infinite (replaced by the floor). Always 0 unless a
    /// bug lets one through; reported so that a bug shows.
    pub nonfinite: usize,
    column_on_atlas: Vec<f32>,
    // Row scratch: x of each column, dh/dx, 1/distance to the eye, 1/S_f's margin, the
    // sketch's curvature.
    x: Vec<f32>,
    gx: Vec<f32>,
    inv_dist: Vec<f32>,
    inv_margin: Vec<f32>,
    curvature: Vec<f32>,
    octave: Vec<f32>,
}

impl ImportanceMap {
    pub fn new(n: usize) -> ImportanceMap {
        ImportanceMap {
            n,
            importance: vec![1.0; n * n],
            frustum: vec![0.0; n * n],
            nonfinite: 0,
            column_on_atlas: Vec::new(),
            x: Vec::new(),
            gx: Vec::new(),
            inv_dist: Vec::new(),
            inv_margin: Vec::new(),
            curvature: Vec::new(),
            octave: Vec::new(),
        }
    }

    /// Bilinear sample of `field` at sketch-map texel coordinates (x, y), clamped to the map.
    pub fn sample(&self, field: &[f32], x: f32, y: f32) -> f32 {
        let n = self.n;
        let x = x.clamp(0.0, (n - 1) as f32);
        let y = y.clamp(0.0, (n - 1) as f32);
        let i = (x as usize).min(n - 2);
        let j = (y as usize).min(n - 2);
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |a: usize, b: usize| field[b * n + a];
        let lo = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
        let hi = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
        lo + (hi - lo) * fy
    }
}
