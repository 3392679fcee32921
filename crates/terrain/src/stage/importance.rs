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
//!   the same order, so the same bits.
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

use crate::camera::Camera;
use crate::stage::sketch_map::{SketchMap, Turn};
use glam::{DVec2, DVec3, Vec3};

/// The frustum factor's margin beyond a texel's reach and the detail's, as a share of the
/// texel's distance to the eye: the room the upsampled mesh's cells take past the texels. A
/// wider margin spends cells, from high up, on ground a kilometre outside the view; a narrower
/// one gains nothing more (docs/decisions.md, “Frustum margin”).
const MARGIN_SHARE: f32 = 0.02;

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

/// Entries of [`ErrorTerm`]'s prefix: octave 0, every octave a scene may have, and one past.
const PREFIX: usize = crate::scene::MAX_OCTAVES as usize + 2;

/// What the geometric-error term needs: its target, its floor and the detail's curvature.
#[derive(Clone, Debug)]
pub struct ErrorTerm {
    /// τ_e: the projected error aimed at, pixels.
    pub target_px: f64,
    /// β: the least share of I_v left on flat ground.
    pub flat_share: f64,
    /// `prefix[k]`: the detail's curvature (1/m) of octaves 1..=k, all fully geometry; past the
    /// last octave, the last value. A fixed size, so that the lookup needs no bounds check.
    prefix: [f32; PREFIX],
    /// The detail's octaves (at most `PREFIX − 2`).
    octaves: usize,
    d_atlas: f64,
    bias: f64,
    /// The water's level: the drawn surface is the sketch or the water, whichever is higher, so
    /// the sketch's part of κ sees the shore as a crease and the water as flat (the octaves'
    /// part is added there all the same).
    water_m: f32,
    /// The mean curvature of each of the sketch's pyramid levels (`Atlas::level_curvature`, NaN
    /// where a level could not be measured); empty until [`ErrorTerm::set_sketch_levels`].
    sketch_levels: Vec<f32>,
}

/// The most segments of a [`SubTexel`]: one per pyramid level between the atlas and the sketch
/// map (a sketch of 2^24 texels a side has 24).
const SUB_TEXEL_SEGMENTS: usize = 24;

/// The sketch's curvature that a sketch map coarser than the atlas cannot see, as a function of
/// a texel's octave level o (as [`ErrorTerm::octave`] gives it), for one frame's map spacing d0.
/// A texel whose sample spacing s lies between the atlas's spacing and d0 meets the curvature of
/// the sketch at its own spacing, and the map holds only that at d0: the difference is taken at
/// its mean over the atlas (`C(s) − C(d0)`, C the levels' mean curvature, linear between
/// levels), since the map cannot say where it lies. Piecewise linear in o: segment j adds
/// `delta·clamp((o − start)·inv_width, 0, 1)`. Each segment adds only an increase of C toward
/// the finer level (a finer level less curved than the one above it adds nothing), so the term
/// is never negative; on natural terrain C grows at every finer level and the two agree. A
/// streamed pyramid's levels not in memory are measured on windows of their tiles
/// (`Atlas::level_curvature`); one that cannot be read is NaN, and counting starts below it.
#[derive(Clone, Copy, Debug)]
struct SubTexel {
    /// (start, end, inv_width, delta) in o, one per segment.
    segments: [[f32; 4]; SUB_TEXEL_SEGMENTS],
    count: usize,
}

impl SubTexel {
    const NONE: SubTexel = SubTexel {
        segments: [[0.0; 4]; SUB_TEXEL_SEGMENTS],
        count: 0,
    };

    /// Adds the curvature to `out` for the row's octave levels `octave`, whose least and
    /// greatest are `(lo, hi)`: a pass over the row for each segment the row's levels cross, a
    /// constant for the segments they all lie beyond.
    #[inline(always)]
    fn add_row(&self, (lo, hi): (f32, f32), octave: &[f32], out: &mut [f32]) {
        let out = &mut out[..octave.len()];
        let mut past = 0.0;
        for &[start, end, inv_width, delta] in &self.segments[..self.count] {
            if hi <= start {
                continue;
            }
            if lo >= end {
                past += delta;
                continue;
            }
            for (v, &o) in out.iter_mut().zip(octave) {
                *v += delta * ((o - start) * inv_width).clamp(0.0, 1.0);
            }
        }
        if past > 0.0 {
            for v in out.iter_mut() {
                *v += past;
            }
        }
    }
}

impl ErrorTerm {
    pub fn new(
        detail: &crate::detail::Detail,
        target_px: f64,
        flat_share: f64,
        water_m: f32,
    ) -> ErrorTerm {
        // The curvature's water clamp is a plain comparison, which a NaN level would poison (the
        // scene checks the level).
        debug_assert!(!water_m.is_nan(), "water level NaN");
        let octaves = (detail.octaves as usize).min(PREFIX - 2);
        let mut prefix = [0.0f32; PREFIX];
        for k in 1..PREFIX {
            let add = if k <= octaves {
                let w = std::f64::consts::TAU * detail.frequency(k as u32);
                crate::detail::NOISE_RMS * detail.weight(k as u32) * w * w
            } else {
                0.0
            };
            prefix[k] = prefix[k - 1] + add as f32;
        }
        ErrorTerm {
            target_px,
            flat_share,
            prefix,
            octaves,
            d_atlas: detail.d_atlas,
            bias: detail.bias,
            water_m,
            sketch_levels: Vec::new(),
        }
    }

    /// The sketch's pyramid levels' mean curvature (`Atlas::level_curvature` at this term's water
    /// level), so that a sketch map coarser than the atlas counts the curvature it cannot see
    /// (`SubTexel`). Without it the term counts only what the map holds.
    pub fn set_sketch_levels(&mut self, curvature: &[f64]) {
        self.sketch_levels = curvature.iter().map(|&c| c as f32).collect();
    }

    /// [`ErrorTerm::set_sketch_levels`] from `atlas`, at the term's water level, unless the term
    /// has its levels already: once for a stage, which serves one sketch.
    pub fn measure_sketch_levels(&mut self, atlas: &crate::sketch::Atlas) {
        if self.sketch_levels.is_empty() {
            self.set_sketch_levels(&atlas.level_curvature(self.water_m));
        }
    }

    /// The [`SubTexel`] curvature for a sketch map of spacing `d0`: none where the map is as fine
    /// as the atlas, or without the levels.
    fn sub_texel(&self, d0: f64) -> SubTexel {
        let mut sub = SubTexel::NONE;
        let levels = &self.sketch_levels;
        // The map's level, and the finest level measured.
        let top = (d0 / self.d_atlas).log2().min(levels.len() as f64 - 1.0);
        let Some(first) = levels.iter().position(|c| c.is_finite()) else {
            return sub;
        };
        if top.is_nan() || top <= first as f64 {
            return sub;
        }
        let c = |l: f64| -> f64 {
            let i = (l.floor() as usize).min(levels.len() - 1);
            let j = (i + 1).min(levels.len() - 1);
            let (a, b) = (f64::from(levels[i]), f64::from(levels[j]));
            a + (b - a) * (l - i as f64)
        };
        // Level l stands for the octave level o = −bias − l (o = log2(d_atlas / s) − bias).
        let mut l = first as f64;
        while l < top && sub.count < SUB_TEXEL_SEGMENTS {
            let next = (l.floor() + 1.0).min(top);
            let delta = (c(l) - c(next)).max(0.0);
            if delta.is_finite() && delta > 0.0 {
                let (start, end) = (-self.bias - next, -self.bias - l);
                sub.segments[sub.count] = [
                    start as f32,
                    end as f32,
                    (1.0 / (next - l)) as f32,
                    delta as f32,
                ];
                sub.count += 1;
            }
            l = next;
        }
        sub
    }

    /// The detail's curvature (1/m) at sample spacing `1 / samples_per_m`: octave k counts with
    /// its geometry share `clamp(o − k + 1, 0, 1)`, `o = log2(d_atlas · samples_per_m) − bias`.
    pub fn detail_curvature(&self, samples_per_m: f32) -> f32 {
        self.curvature_at(self.octave(samples_per_m))
    }

    /// The octave level o at sample spacing `1 / samples_per_m` (0 for NaN; below 0 where the
    /// spacing is coarser than the first octave's, which [`ErrorTerm::curvature_at`] and
    /// `SubTexel` tell apart):
    /// `log2` to 2·10⁻⁵ of an octave in operations that vectorise: `f32::log2` is a library
    /// call per texel.
    #[inline(always)]
    pub fn octave(&self, samples_per_m: f32) -> f32 {
        let x = self.d_atlas as f32 * samples_per_m;
        let o = log2_approx(x) - self.bias as f32;
        if x.is_nan() { 0.0 } else { o }
    }

    /// The detail's curvature at octave level `o` (a level below 0 counts as 0: no octave is
    /// geometry there).
    #[inline(always)]
    pub fn curvature_at(&self, o: f32) -> f32 {
        // Within [0, octaves], so the cast is floor; past the last octave the prefix is flat.
        let o = o.clamp(0.0, self.octaves as f32);
        let whole = (o as u32 as usize).min(PREFIX - 2);
        let (p0, p1) = (self.prefix[whole], self.prefix[whole + 1]);
        p0 + (p1 - p0) * (o - whole as f32)
    }

    /// Adds the detail's curvature at each octave level of `octave` (as [`ErrorTerm::octave`]
    /// gives them; `range` their least and greatest, [`octave_range`]) to `out`:
    /// [`ErrorTerm::curvature_at`] summed segment by segment,
    /// `prefix[k₀] + Σ_k (prefix[k+1] − prefix[k])·clamp(o − k, 0, 1)` over the octaves
    /// between the row's least and greatest level (k₀ the least's whole part), so that it
    /// vectorises. The same value to a few ulps (`the_row_curvature_follows_the_lookup`).
    ///
    /// A row's levels span a few octaves (its distances to the eye), so this is a few passes
    /// over the row. A lookup in the prefix per texel stays scalar (LLVM does not gather from
    /// it).
    #[inline(always)]
    fn add_curvature_row(&self, range: (f32, f32), octave: &[f32], out: &mut [f32]) {
        let n = octave.len();
        let out = &mut out[..n];
        // A level below 0 counts as 0: no octave is geometry there.
        let top = self.octaves as f32;
        let (lo, hi) = (range.0.clamp(0.0, top), range.1.clamp(0.0, top));
        // Within [0, octaves], so the casts are floor and ceil's integer part.
        let first = (lo as usize).min(PREFIX - 2);
        let last = (hi.ceil() as usize).min(self.octaves);
        let base = self.prefix[first];
        for v in out.iter_mut() {
            *v += base;
        }
        for k in first..last {
            let slope = self.prefix[k + 1] - self.prefix[k];
            let kf = k as f32;
            for (v, &o) in out.iter_mut().zip(octave) {
                *v += slope * (o - kf).clamp(0.0, 1.0);
            }
        }
    }
}

/// The least and greatest of a row's octave levels (never NaN: [`ErrorTerm::octave`] gives 0 for
/// NaN). Lanes of minima and maxima, so that the reduction vectorises; plain comparisons, as
/// f32::min and max's NaN blends, over chunks of varying length, took a tenth of the importance
/// map.
#[inline(always)]
fn octave_range(octave: &[f32]) -> (f32, f32) {
    const ACC: usize = 16;
    let (mut lo, mut hi) = ([f32::INFINITY; ACC], [f32::NEG_INFINITY; ACC]);
    let chunks = octave.chunks_exact(ACC);
    let rest = chunks.remainder();
    for chunk in chunks {
        let chunk: &[f32; ACC] = chunk.try_into().expect("a whole chunk");
        for l in 0..ACC {
            let o = chunk[l];
            lo[l] = if o < lo[l] { o } else { lo[l] };
            hi[l] = if o > hi[l] { o } else { hi[l] };
        }
    }
    for &o in rest {
        lo[0] = if o < lo[0] { o } else { lo[0] };
        hi[0] = if o > hi[0] { o } else { hi[0] };
    }
    let lo = lo.into_iter().fold(f32::INFINITY, f32::min);
    let hi = hi.into_iter().fold(f32::NEG_INFINITY, f32::max);
    (lo, hi)
}

/// log2 of a positive f32 to within 2·10⁻⁵: the exponent, plus a quintic in the mantissa m in
/// [1, 2) fitted to log2 m at Chebyshev nodes. 0 and subnormals give about −127, infinity 128,
/// a negative x log2 |x|, and NaN is left to the caller.
#[inline(always)]
fn log2_approx(x: f32) -> f32 {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let p = -2.794_153_7
        + m * (5.069_756_3
            + m * (-3.520_218_8 + m * (1.610_177_5 + m * (-0.409_475_6 + m * 0.043_928_63))));
    e as f32 + p
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

    /// Fills the map for `camera` over `map`; `surface_max` is I_s per texel when a map gives it.
    /// Allocates nothing after the first frame.
    pub fn update(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
    ) {
        self.update_rows(map, atlas_bounds, camera, surface_max, p, 1);
    }

    /// [`ImportanceMap::update`] for every `row_step`-th row only (0, row_step, …); the other
    /// rows keep what they held. A held warp's drift check (`stage::hold`) samples the map so.
    pub fn update_rows(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
        row_step: usize,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::stage::simd::avx512() {
            // SAFETY: the processor has AVX-512F and AVX2 (`simd::avx512`), checked just above.
            unsafe { self.rows_avx512(map, atlas_bounds, camera, surface_max, p, row_step) };
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::stage::simd::avx2() {
            // SAFETY: the processor has AVX2, checked just above.
            unsafe { self.rows_avx2(map, atlas_bounds, camera, surface_max, p, row_step) };
            return;
        }
        self.rows(map, atlas_bounds, camera, surface_max, p, row_step);
    }

    /// [`ImportanceMap::rows`] compiled for AVX-512's sixteen f32 lanes: the same loops in
    /// registers twice as wide. The same operations in the same order: the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2")]
    unsafe fn rows_avx512(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
        row_step: usize,
    ) {
        self.rows(map, atlas_bounds, camera, surface_max, p, row_step);
    }

    /// [`ImportanceMap::rows`] compiled for AVX2's eight f32 lanes (the build's baseline, SSE2,
    /// has four). The same operations in the same order: the results are bit-identical.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn rows_avx2(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
        row_step: usize,
    ) {
        self.rows(map, atlas_bounds, camera, surface_max, p, row_step);
    }

    // The row loops index five parallel slices by column; zipped iterators would hide that.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn rows(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
        row_step: usize,
    ) {
        let n = map.n;
        let d0 = map.spacing;
        let corner = map.origin.extend(0.0);
        // Region-local: x and y along the region's axes (`SketchMap::local`), z up.
        let local = |v: DVec3| map.turn.frame(v.truncate()).extend(v.z);
        let eye = local(camera.eye - corner).as_vec3();
        // Each plane's distance is linear in the texel's (x, y, z): a·x + b·y + c·z + d.
        let planes = camera
            .planes()
            .map(|pl| (local(pl.n).as_vec3(), (pl.d + pl.n.dot(corner)) as f32));
        let k_view = (camera.f_px() / p.quad_px) as f32;
        let inv_d_min = (2.0 / d0) as f32;
        let centre = map.world(DVec2::splat(0.5 * map.extent()));
        let uniform_view = (camera.f_px()
            / (p.quad_px * (camera.eye - centre.extend(0.0)).length().max(d0)))
            as f32;
        let margin_base = (1.5 * d0 + p.reach_m) as f32;
        let i_s_const = p.max_per_m.map_or(f32::INFINITY, |v| v as f32);
        let d0f = d0 as f32;
        let floor_b = p.backface_floor as f32;

        // Which texels lie on the atlas: a range of columns and of rows.
        let inside = |lo: f64, hi: f64, o: f64| {
            let first = ((lo - o) / d0 - 1e-6).ceil().max(0.0);
            let last = ((hi - o) / d0 + 1e-6).floor().min((n - 1) as f64);
            (first as usize, last.max(first - 1.0) as isize)
        };
        let (i_first, i_last) = inside(atlas_bounds.0.x, atlas_bounds.1.x, map.origin.x);
        let (j_first, j_last) = inside(atlas_bounds.0.y, atlas_bounds.1.y, map.origin.y);
        let turned = map.turn != Turn::None;
        self.column_on_atlas.resize(n, 0.0);
        fill_on_atlas(&mut self.column_on_atlas, (i_first, i_last));
        self.gx.resize(n, 0.0);
        self.inv_dist.resize(n, 0.0);
        self.inv_margin.resize(n, 0.0);
        self.curvature.resize(n, 0.0);
        self.octave.resize(n, 0.0);
        let f_px = camera.f_px() as f32;
        self.x.resize(n, 0.0);
        for (i, x) in self.x.iter_mut().enumerate() {
            *x = i as f32 * d0f;
        }

        let sub_texel = p.error.as_ref().map_or(SubTexel::NONE, |e| e.sub_texel(d0));
        let h = &map.heights;
        const ACC: usize = 16;
        let mut min_visible = [f32::INFINITY.to_bits(); ACC];
        let mut nonfinite = [0u32; ACC];
        // Every row buffer sliced to n once: an index into a buffer of unknown length is checked
        // in the loop, and a checked loop stays scalar (the distance and S_b loops did, a quarter
        // of the map's time).
        let ImportanceMap {
            x,
            gx,
            inv_dist,
            inv_margin,
            curvature,
            octave,
            column_on_atlas,
            frustum,
            importance,
            ..
        } = self;
        let (x, gx, inv_dist) = (&x[..n], &mut gx[..n], &mut inv_dist[..n]);
        let inv_margin = &mut inv_margin[..n];
        let (curvature, column_on_atlas) = (&mut curvature[..n], &mut column_on_atlas[..n]);
        let octave = &mut octave[..n];
        for j in (0..n).step_by(row_step.max(1)) {
            let y = j as f32 * d0f;
            let row_on = if turned {
                // A turned region's row crosses the atlas's edges at its own columns.
                let (base, step) = (map.texel_world(0, j), map.turn.axes().0 * d0);
                fill_on_atlas(column_on_atlas, on_atlas(base, step, n, atlas_bounds));
                1.0
            } else if j >= j_first && (j as isize) <= j_last {
                1.0
            } else {
                0.0
            };
            let (jm, jp) = (j.saturating_sub(1), (j + 1).min(n - 1));
            let row = &h[j * n..(j + 1) * n];
            let (down, up) = (&h[jm * n..(jm + 1) * n], &h[jp * n..(jp + 1) * n]);
            let dy = eye.y - y;
            // Each part is a plain loop over the row, so that it vectorises.
            for i in 0..n {
                let (dx, dz) = (eye.x - x[i], eye.z - row[i]);
                inv_dist[i] = 1.0 / (dx * dx + dy * dy + dz * dz).sqrt().max(1e-6);
            }
            let s_f = &mut frustum[j * n..(j + 1) * n];
            for i in 0..n {
                s_f[i] = row_on * column_on_atlas[i];
            }
            if p.frustum {
                for i in 0..n {
                    let margin = margin_base + MARGIN_SHARE / inv_dist[i];
                    inv_margin[i] = 1.0 / margin;
                }
                let (h_lo, h_hi) = row
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| {
                        (lo.min(h), hi.max(h))
                    });
                // A row with a NaN or infinite height (which f32::min and max pass over) skips no
                // plane, so that the non-finite shows. An or of flags, so that it vectorises (a
                // sum of `h − h` does not).
                let finite = !row.iter().fold(false, |bad, h| bad | !h.is_finite());
                // A plane's factors multiply in plane order, one pass over the row each; a plane
                // that has the whole row inside gives 1 to every texel and is skipped.
                for (pn, pd) in planes {
                    let plane_row = pn.y * y + pd;
                    if finite && row_inside(pn, plane_row, x[n - 1], (h_lo, h_hi)) {
                        continue;
                    }
                    for i in 0..n {
                        let dist_p = pn.x * x[i] + pn.z * row[i] + plane_row;
                        s_f[i] *= smoothstep(dist_p * inv_margin[i] + 1.0);
                    }
                }
            }
            let out = &mut importance[j * n..(j + 1) * n];
            for i in 0..n {
                out[i] = if p.view {
                    k_view * inv_dist[i].min(inv_d_min)
                } else {
                    uniform_view
                };
            }
            if let Some(e) = &p.error {
                sketch_curvature([down, row, up], jp - jm, d0f, e.water_m, curvature);
                let k_error = f_px / (8.0 * e.target_px as f32);
                let flat = e.flat_share as f32;
                for i in 0..n {
                    octave[i] = e.octave(out[i]);
                }
                let range = octave_range(octave);
                e.add_curvature_row(range, octave, curvature);
                sub_texel.add_row(range, octave, curvature);
                for i in 0..n {
                    let i_v = out[i];
                    let i_g = (curvature[i] * k_error * inv_dist[i].min(inv_d_min)).sqrt();
                    out[i] = i_v.min(i_g.max(flat * i_v));
                }
            }
            if p.backface {
                slope_x(row, d0f, gx);
                let gy_scale = 1.0 / ((jp - jm) as f32 * d0f);
                for i in 0..n {
                    let (gx, gy) = (gx[i], (up[i] - down[i]) * gy_scale);
                    let (dx, dz) = (eye.x - x[i], eye.z - row[i]);
                    let facing = (dz - gx * dx - gy * dy) * inv_dist[i];
                    out[i] *= backface(facing / (gx * gx + gy * gy + 1.0).sqrt(), floor_b);
                }
            }
            let i_s_row = surface_max.map(|m| &m[j * n..(j + 1) * n]);
            for i in 0..n {
                let i_s = i_s_row.map_or(i_s_const, |m| m[i].min(i_s_const));
                out[i] = (out[i] * s_f[i]).min(i_s);
            }
            // Lanes of counts and minima, so that the loop vectorises: one running f32::min is a
            // chain the compiler must keep in order (it took 40 % of the map's time). Whole
            // chunks of a fixed length, then the rest: chunks of varying length took a fifth.
            let whole = n / ACC * ACC;
            let chunks = out[..whole]
                .chunks_exact_mut(ACC)
                .zip(s_f[..whole].chunks_exact(ACC));
            for (out, s_f) in chunks {
                let out: &mut [f32; ACC] = out.try_into().expect("a whole chunk");
                let s_f: &[f32; ACC] = s_f.try_into().expect("a whole chunk");
                for l in 0..ACC {
                    tally(&mut out[l], s_f[l], &mut min_visible[l], &mut nonfinite[l]);
                }
            }
            for (v, &s) in out[whole..].iter_mut().zip(&s_f[whole..]) {
                tally(v, s, &mut min_visible[0], &mut nonfinite[0]);
            }
        }
        self.nonfinite = nonfinite.iter().map(|&c| c as usize).sum();
        let min_visible = f32::from_bits(min_visible.into_iter().min().expect("ACC lanes"));
        self.apply_floor(min_visible, p.floor as f32, row_step.max(1));
    }

    // Inlined into the row loops' builds (AVX-512, AVX2): on its own it is built for the
    // baseline's four lanes.
    #[inline(always)]
    fn apply_floor(&mut self, min_visible: f32, floor: f32, row_step: usize) {
        let n = self.n;
        let rows = self.importance.chunks_exact_mut(n).step_by(row_step);
        if !min_visible.is_finite() {
            rows.for_each(|r| r.fill(1.0));
            return;
        }
        let i_floor = (min_visible * floor).max(f32::MIN_POSITIVE);
        for row in rows {
            for v in row {
                *v = v.max(i_floor);
            }
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

/// A texel's final importance `v`: 0 where it is not finite or negative (counted in
/// `nonfinite`), and the least positive one in view (`s_f ≥ ½`) so far in `min_visible` (its
/// bits).
#[inline(always)]
fn tally(v: &mut f32, s_f: f32, min_visible: &mut u32, nonfinite: &mut u32) {
    let finite = v.is_finite() && *v >= 0.0;
    let x = if finite { *v } else { 0.0 };
    *v = x;
    *nonfinite += u32::from(!finite);
    let candidate = if s_f >= 0.5 && x > 0.0 {
        x
    } else {
        f32::INFINITY
    };
    // x is positive or infinity here, whose bits order as the values do: an integer minimum is
    // one instruction, where a conditional store of the f32 became a masked store that the next
    // chunk's load of the same lanes waited on (a tenth of the map's time).
    *min_visible = (*min_visible).min(candidate.to_bits());
}

/// The largest second derivative of the sketch map's heights along a row (1/m): |h_xx|, |h_yy|
/// and |h_xy| from the rows `down` and `up` `rows_apart` rows apart around it (1 at the map's
/// edge, where one of them is the row itself and `h_yy` is taken as 0), one-sided at the ends.
// The loop indexes each texel's neighbours; an iterator over `out` would hide them.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn sketch_curvature(
    [down, row, up]: [&[f32]; 3],
    rows_apart: usize,
    d0: f32,
    water: f32,
    out: &mut [f32],
) {
    let n = row.len();
    let (down, up, out) = (&down[..n], &up[..n], &mut out[..n]);
    let inv = 1.0 / (d0 * d0);
    let y_second = if rows_apart == 2 { 1.0 } else { 0.0 };
    // Texel i from its neighbours l and r along the row.
    #[inline(always)]
    fn at(h: [&[f32]; 3], i: usize, l: usize, r: usize, inv: f32, y: (f32, usize), w: f32) -> f32 {
        // Ground under water is the water's flat surface. A plain comparison: f32::max's NaN
        // blend costs two instructions a texel, and gives the same (w) for a NaN height; the
        // water level is never NaN (the scene checks it).
        let [down, row, up] = h.map(|line| {
            move |k: usize| {
                let v = line[k];
                if v > w { v } else { w }
            }
        });
        let hxx = if r - l == 2 {
            (row(r) - 2.0 * row(i) + row(l)) * inv
        } else {
            0.0
        };
        let hyy = (up(i) - 2.0 * row(i) + down(i)) * inv * y.0;
        // A power of two (1, 2 or 4), so a product by its reciprocal is the quotient to the bit,
        // and the reciprocal is the same for the whole inner loop, which a division per texel
        // kept from hoisting.
        let span = ((r - l) * y.1).max(1) as f32;
        let hxy = (up(r) - up(l) - down(r) + down(l)) * inv * (1.0 / span);
        hxx.abs().max(hyy.abs()).max(hxy.abs())
    }
    let (h, y) = ([down, row, up], (y_second, rows_apart));
    // The ends apart, so that the inner loop has fixed neighbours and vectorises.
    for i in [0, n - 1] {
        out[i] = at(h, i, i.saturating_sub(1), (i + 1).min(n - 1), inv, y, water);
    }
    // Runs of RUN texels, the last one overlapping the one before (its texels are computed
    // twice, to the same values), so that no texel is left to a scalar remainder loop. The runs
    // borrow the rows in place: loads at an offset from a stack copy's stores would wait for
    // them.
    const RUN: usize = 16;
    if n < RUN + 2 {
        for i in 1..n - 1 {
            out[i] = at(h, i, i - 1, i + 1, inv, y, water);
        }
        return;
    }
    let mut i0 = 1;
    loop {
        fn w(line: &[f32], i0: usize) -> &[f32; RUN + 2] {
            line[i0 - 1..i0 + RUN + 1]
                .try_into()
                .expect("a run and its ends")
        }
        let (d, r, u) = (w(down, i0), w(row, i0), w(up, i0));
        let run: &mut [f32; RUN] = (&mut out[i0..i0 + RUN]).try_into().expect("a run");
        for k in 0..RUN {
            run[k] = at([d, r, u], k + 1, k, k + 2, inv, y, water);
        }
        if i0 + RUN >= n - 1 {
            break;
        }
        i0 = (i0 + RUN).min(n - 1 - RUN);
    }
}

/// dh/dx along a row: central differences inside, one-sided at the ends.
fn slope_x(row: &[f32], d0: f32, out: &mut [f32]) {
    let n = row.len();
    let half = 0.5 / d0;
    for i in 1..n - 1 {
        out[i] = (row[i + 1] - row[i - 1]) * half;
    }
    out[0] = (row[1] - row[0]) / d0;
    out[n - 1] = (row[n - 1] - row[n - 2]) / d0;
}

/// Whether every texel of a row (x in [0, `x_max`], heights in `h`) is surely on the inner side
/// of a plane, `n·(x, y, z) + d ≥ 0` with `d` at the row's y: its least value over the row's box,
/// less an allowance for the f32 rounding of the per-texel sum (about 50 times the few ulps of
/// its terms that rounding can cost), is positive. The texels' smoothsteps are then exactly 1.
fn row_inside(pn: Vec3, d: f32, x_max: f32, (h_lo, h_hi): (f32, f32)) -> bool {
    let (a, c, d) = (pn.x as f64, pn.z as f64, d as f64);
    let (x_max, h_lo, h_hi) = (x_max as f64, h_lo as f64, h_hi as f64);
    let least = d + (a * x_max).min(0.0) + (c * h_lo).min(c * h_hi);
    let scale = d.abs() + (a * x_max).abs() + (c * h_lo).abs().max((c * h_hi).abs());
    least.is_finite() && least > 1e-5 * scale
}

fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// S_b from the cosine between the surface normal and the direction to the eye.
fn backface(cos: f32, floor: f32) -> f32 {
    const SILHOUETTE: f32 = -0.05;
    const FADE: f32 = 0.3;
    let t = ((SILHOUETTE - cos) / FADE).clamp(0.0, 1.0);
    1.0 - (1.0 - floor) * smoothstep(t)
}

/// 1 for the columns in `first ..= last`, 0 elsewhere.
fn fill_on_atlas(on: &mut [f32], (first, last): (usize, isize)) {
    for (i, v) in on.iter_mut().enumerate() {
        *v = if i >= first && (i as isize) <= last {
            1.0
        } else {
            0.0
        };
    }
}

/// The texels `base + i·step`, i < n, that lie on the atlas `[lo, hi]` (a slack of 10⁻⁶ texel,
/// as for an axis-aligned region): `(first, last)`, empty when last < first.
fn on_atlas(base: DVec2, step: DVec2, n: usize, (lo, hi): (DVec2, DVec2)) -> (usize, isize) {
    let (mut first, mut last) = (0.0f64, (n - 1) as f64);
    for axis in 0..2 {
        let (b, d) = (base[axis], step[axis]);
        if d.abs() < 1e-12 {
            if b < lo[axis] || b > hi[axis] {
                return (1, 0);
            }
            continue;
        }
        let (a, c) = ((lo[axis] - b) / d, (hi[axis] - b) / d);
        first = first.max(a.min(c) - 1e-6);
        last = last.min(a.max(c) + 1e-6);
    }
    let (first, last) = (first.ceil(), last.floor());
    // f64::max and min pass over a NaN (a non-finite corner), which then leaves the row on the
    // atlas, as the axis-aligned range does; a NaN here cannot arise, but would leave it off.
    match first.partial_cmp(&last) {
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal) => {
            (first as usize, last as isize)
        }
        _ => (1, 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled scenes' detail (8 m, gain 0.45) at the default bias, over `d_atlas`.
    fn bundled_detail(d_atlas: f64, lattice_origin_m: DVec2) -> crate::detail::Detail {
        crate::detail::Detail {
            octaves: 12,
            amplitude_m: 8.0,
            gain: 0.45,
            seed: 7,
            bias: -1.0,
            d_atlas,
            lattice_origin_m,
        }
    }

    /// The sub-texel curvature: the sketch's mean curvature at the texel's spacing less the
    /// map's, linear between levels, none past the map's level or the atlas's, none for a map as
    /// fine as the atlas, and only the levels measured (not NaN). A segment's sign, width or offset
    /// wrong (or the bias's sign) breaks the values at whole and half levels.
    #[test]
    fn the_sub_texel_curvature_is_what_the_map_cannot_see() {
        let d_atlas = 30.0;
        let mut e = ErrorTerm::new(&bundled_detail(d_atlas, DVec2::ZERO), 0.5, 0.125, 0.0);
        let c = [8e-3, 4e-3, 2e-3, 1e-3, 5e-4];
        e.set_sketch_levels(&c);
        // The texel's spacing at pyramid level l (fractional): its samples per metre.
        let per_m = |l: f64| (1.0 / (d_atlas * l.exp2())) as f32;
        let at = |e: &ErrorTerm, d0: f64, l: f64| {
            let octave = [e.octave(per_m(l))];
            let mut out = [0.0f32];
            e.sub_texel(d0)
                .add_row(octave_range(&octave), &octave, &mut out);
            out[0]
        };
        let close = |got: f32, want: f64| (f64::from(got) - want).abs() <= 1e-4 * want + 1e-7;
        // The map at level 2 (4·d_atlas): C(l) − C(2) from level 0 to 2.
        let d0 = 4.0 * d_atlas;
        for (l, want) in [
            (-1.5, 6e-3),
            (0.0, 6e-3),
            (0.5, 4e-3),
            (1.0, 2e-3),
            (1.5, 1e-3),
            (2.0, 0.0),
            (3.0, 0.0),
        ] {
            let got = at(&e, d0, l);
            assert!(close(got, want), "level {l}: {got} vs {want}");
        }
        // The map at level 2.5: C(2.5) = 1.5e-3.
        let got = at(&e, 2f64.powf(2.5) * d_atlas, 1.0);
        assert!(close(got, 2.5e-3), "map at 2.5, level 1: {got}");
        // A map as fine as the atlas, or finer: nothing to add.
        for d0 in [d_atlas, 0.5 * d_atlas] {
            assert_eq!(at(&e, d0, 0.0), 0.0);
        }
        // A streamed pyramid without its two finest levels: only from level 2 on.
        e.set_sketch_levels(&[f64::NAN, f64::NAN, 2e-3, 1e-3, 5e-4]);
        let got = at(&e, 16.0 * d_atlas, 0.0);
        assert!(close(got, 1.5e-3), "streamed: {got}");
        // A row whose levels span every segment gives each texel what it gives alone (the row's
        // passes and the constant for the segments the whole row lies beyond).
        e.set_sketch_levels(&c);
        let d0 = 8.0 * d_atlas;
        // A row finer than the map's two coarser segments takes them as one constant.
        for levels in [
            (0..37).map(|i| 3.6 - 0.1 * i as f64).collect::<Vec<f64>>(),
            (0..21).map(|i| 0.5 - 0.05 * i as f64).collect(),
        ] {
            let octave: Vec<f32> = levels.iter().map(|&l| e.octave(per_m(l))).collect();
            let mut row = vec![0.0f32; octave.len()];
            e.sub_texel(d0)
                .add_row(octave_range(&octave), &octave, &mut row);
            for (&l, &got) in levels.iter().zip(&row) {
                let want = at(&e, d0, l);
                assert!(
                    (got - want).abs() <= 1e-6 * want + 1e-9,
                    "level {l}: {got} vs {want}"
                );
            }
        }
        // Without the levels, nothing.
        let plain = ErrorTerm::new(&bundled_detail(d_atlas, DVec2::ZERO), 0.5, 0.125, 0.0);
        assert_eq!(at(&plain, d0, 0.0), 0.0);
    }

    /// The AVX2 build of the row loops gives the baseline build's values, bit for bit (on a
    /// processor without AVX2 both are the baseline).
    #[test]
    fn every_build_of_the_rows_gives_the_same_bits() {
        use crate::sketch::{Atlas, LoadOptions};
        use glam::DVec3;
        let atlas = Atlas::synthetic("hills", 257, &LoadOptions::default()).unwrap();
        let eye = DVec3::new(2000.0, 1500.0, 900.0);
        let camera = Camera::new(
            eye,
            DVec3::new(4000.0, 5000.0, 300.0),
            60.0,
            512,
            512,
            9000.0,
        )
        .unwrap();
        let mut map = SketchMap::new(128);
        map.update(&atlas, &camera, 50.0, false, Turn::None);
        let p = ImportanceParams {
            quad_px: 2.0,
            view: true,
            frustum: true,
            backface: true,
            max_per_m: None,
            floor: 0.1,
            backface_floor: 0.15,
            reach_m: 50.0,
            error: None,
        };
        let bounds = (atlas.origin, atlas.max_corner());
        let detail = bundled_detail(atlas.d_atlas(), atlas.origin);
        // Without and with the geometric-error term (the default), water over part of the hills,
        // and without octaves (whose curvature here asks for more than I_v everywhere), without
        // and with the sketch's levels, so that the sub-texel curvature's segments run and count.
        let error = ErrorTerm::new(&detail, 0.5, 0.125, atlas.min_m + 20.0);
        let bare = crate::detail::Detail {
            octaves: 0,
            ..detail.clone()
        };
        let error_bare = ErrorTerm::new(&bare, 0.5, 0.125, atlas.min_m + 20.0);
        let mut with_levels = error_bare.clone();
        with_levels.set_sketch_levels(&[8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1.2e-4, 6e-5]);
        assert!(
            with_levels.sub_texel(map.spacing).count > 0,
            "the map is coarser than the atlas"
        );
        let mut importance = Vec::new();
        for p in [
            p.clone(),
            ImportanceParams {
                error: Some(error),
                ..p.clone()
            },
            ImportanceParams {
                error: Some(error_bare),
                ..p.clone()
            },
            ImportanceParams {
                error: Some(with_levels),
                ..p
            },
        ] {
            let (mut dispatched, mut baseline) = (ImportanceMap::new(128), ImportanceMap::new(128));
            dispatched.update(&map, bounds, &camera, None, &p);
            baseline.rows(&map, bounds, &camera, None, &p, 1);
            let bits =
                |m: &ImportanceMap| m.importance.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            // The AVX2 build too, where the dispatch took AVX-512.
            #[cfg(target_arch = "x86_64")]
            if crate::stage::simd::avx2() {
                let mut avx2 = ImportanceMap::new(128);
                // SAFETY: the processor has AVX2, checked just above.
                unsafe { avx2.rows_avx2(&map, bounds, &camera, None, &p, 1) };
                assert_eq!(bits(&avx2), bits(&baseline), "AVX2");
            }
            assert_eq!(
                bits(&dispatched),
                bits(&baseline),
                "error term: {}",
                p.error.is_some()
            );
            assert!(
                dispatched
                    .importance
                    .iter()
                    .any(|&v| v != dispatched.importance[0])
            );
            importance.push(dispatched.importance);
        }
        // The levels reach the map: the sub-texel curvature raises the error term's importance.
        let raised = importance[3]
            .iter()
            .zip(&importance[2])
            .filter(|(a, b)| a > b)
            .count();
        assert!(
            raised > 1000,
            "{raised} texels raised by the sketch's levels"
        );
    }

    /// The vectorised log2 keeps its bound from 10⁻³⁰ to 10³⁰, and the error term's curvature
    /// through it follows the one through `f64::log2` (a wrong polynomial, ln for log2, is off
    /// by 0.3 and fails both).
    #[test]
    fn the_octave_level_follows_the_exact_log2() {
        let mut worst = 0.0f64;
        let mut x = 1e-30f64;
        while x < 1e30 {
            for v in [x as f32, (x * (1.0 + 1e-6)) as f32, (x as f32).next_down()] {
                worst = worst.max((log2_approx(v) as f64 - (v as f64).log2()).abs());
            }
            x *= 1.0137;
        }
        assert!(worst < 2e-5, "log2 off by {worst}");
        let detail = bundled_detail(30.0, DVec2::ZERO);
        let e = ErrorTerm::new(&detail, 0.5, 0.125, f32::NEG_INFINITY);
        let mut s = 1e-4f64;
        while s < 1e3 {
            let o = ((30.0 * s).log2() + 1.0).max(0.0) as f32;
            let (got, want) = (e.detail_curvature(s as f32), e.curvature_at(o));
            // Piecewise linear in o: an error of 2·10⁻⁵ in o moves it by that times the
            // steeper of the two segments around o.
            let w = (o as usize).min(11);
            let slope = (e.prefix[w + 2] - e.prefix[w + 1]).max(e.prefix[w + 1] - e.prefix[w]);
            let allowed = 2e-5 * slope + 1e-6 * want;
            assert!((got - want).abs() <= allowed, "{s}: {got} vs {want}");
            s *= 1.07;
        }
        assert_eq!(e.octave(f32::NAN), 0.0);
        // No samples: far below the first octave, and no octave's curvature.
        assert!(e.octave(0.0) < -100.0);
        assert_eq!(e.detail_curvature(0.0), 0.0);
        assert_eq!(e.detail_curvature(f32::INFINITY), e.curvature_at(12.0));
    }

    /// The row's segment sums give what the per-texel lookup gives: rows whose levels lie within
    /// one octave, across several, on whole octaves, at 0 and past the last octave (dropping the
    /// base, or the last segment, is off by a whole octave's curvature).
    #[test]
    fn the_row_curvature_follows_the_lookup() {
        let detail = bundled_detail(30.0, DVec2::ZERO);
        let e = ErrorTerm::new(&detail, 0.5, 0.125, f32::NEG_INFINITY);
        let mut next = crate::stage::lines::tests::uniform(0x51ed_270b);
        let rows: Vec<Vec<f32>> = vec![
            (0..128).map(|_| 3.2 + 0.5 * next()).collect(),
            (0..128).map(|_| 14.0 * next()).collect(),
            (0..128).map(|i| (i % 13) as f32).collect(),
            (0..128)
                .map(|i| if i % 2 == 0 { 0.0 } else { 30.0 })
                .collect(),
            (0..128).map(|_| 11.5 + next()).collect(),
            vec![0.0; 128],
            // Levels below 0 (spacings coarser than the first octave's) count as 0.
            (0..128).map(|_| 2.0 - 6.0 * next()).collect(),
            // 37 texels: two chunks of sixteen and a rest of five holding the least and the
            // greatest level, which the rest's own comparisons must find.
            (0..37)
                .map(|i| if i < 32 { 5.5 } else { 2.2 + i as f32 / 8.0 })
                .collect(),
        ];
        for (r, octave) in rows.iter().enumerate() {
            let n = octave.len();
            let sketch: Vec<f32> = (0..n).map(|_| 1e-3 * next()).collect();
            let mut got = sketch.clone();
            e.add_curvature_row(octave_range(octave), octave, &mut got);
            for i in 0..n {
                let want = sketch[i] + e.curvature_at(octave[i]);
                assert!(
                    (got[i] - want).abs() <= 1e-5 * want.abs() + 1e-9,
                    "row {r} texel {i} at level {}: {} vs {want}",
                    octave[i],
                    got[i]
                );
            }
        }
    }

    /// The sketch's curvature in runs (the last overlapping the one before) gives, at every
    /// texel, what the three differences give one texel at a time: rows of fewer texels than a
    /// run and a pair of ends, of exactly that, one more, and runs that overlap by 1 and by 13;
    /// with water above some of the ground, a NaN height (the water's level there), and a row at
    /// the map's edge (`rows_apart` 1).
    #[test]
    fn the_sketch_curvature_in_runs_follows_each_texel() {
        let mut next = crate::stage::lines::tests::uniform(0x7a3c_11e5);
        let (d0, water) = (7.5f32, 40.0f32);
        for n in [3usize, 17, 18, 19, 33, 37, 128] {
            let mut line = || -> Vec<f32> { (0..n).map(|_| 100.0 * next()).collect() };
            let (down, mut row, up) = (line(), line(), line());
            row[n / 2] = f32::NAN;
            for rows_apart in [2usize, 1] {
                let down = if rows_apart == 2 { &down } else { &row };
                let mut got = vec![f32::NAN; n];
                sketch_curvature([down, &row, &up], rows_apart, d0, water, &mut got);
                let h = |line: &[f32], k: usize| {
                    let v = line[k];
                    if v.is_nan() { water } else { v.max(water) }
                };
                for (i, got) in got.iter().enumerate() {
                    let (l, r) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    let inv = 1.0 / (d0 * d0);
                    let hxx = if r - l == 2 {
                        (h(&row, r) - 2.0 * h(&row, i) + h(&row, l)) * inv
                    } else {
                        0.0
                    };
                    let hyy = if rows_apart == 2 {
                        (h(&up, i) - 2.0 * h(&row, i) + h(down, i)) * inv
                    } else {
                        0.0
                    };
                    let span = ((r - l) * rows_apart) as f32;
                    let hxy = (h(&up, r) - h(&up, l) - h(down, r) + h(down, l)) * inv / span;
                    let want = hxx.abs().max(hyy.abs()).max(hxy.abs());
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "n {n} apart {rows_apart} texel {i}"
                    );
                }
            }
        }
    }

    /// A NaN height in a row wholly in view still shows as a non-finite texel: the plane skip
    /// must not pass over it (f32::min and max ignore NaN, and the distance's `max(1e-6)` does).
    #[test]
    fn a_nan_height_in_a_row_in_view_is_counted() {
        use glam::DVec3;
        // 16 texels a row; and 19, with the NaN in the three past the last whole chunk, which
        // the final loop tallies apart.
        for (n, nan_at) in [(16usize, 7usize), (19, 17)] {
            let mut map = SketchMap::new(n);
            map.spacing = 10.0;
            map.heights[5 * n + nan_at] = f32::NAN;
            // High above the map's centre, looking straight down: every texel is well inside.
            let c = 5.0 * (n - 1) as f64;
            let camera = Camera::new(
                DVec3::new(c, c, 2000.0),
                DVec3::new(c, c + 0.001, 0.0),
                60.0,
                64,
                64,
                10_000.0,
            )
            .unwrap();
            let p = ImportanceParams {
                quad_px: 2.0,
                view: true,
                frustum: true,
                backface: false,
                max_per_m: None,
                floor: 0.1,
                backface_floor: 0.15,
                reach_m: 5.0,
                error: None,
            };
            let bounds = (DVec2::ZERO, DVec2::splat(10.0 * (n - 1) as f64));
            let mut imp = ImportanceMap::new(n);
            imp.update(&map, bounds, &camera, None, &p);
            assert_eq!(imp.nonfinite, 1, "n {n}");
            assert!(imp.importance.iter().all(|v| v.is_finite() && *v > 0.0));
            // Every other texel is in view: a plane the row has inside is skipped there.
            assert!(imp.frustum.iter().filter(|f| **f == 1.0).count() >= n * n - 1);
        }
    }

    /// A plane skipped for a row leaves S_f as evaluating it would have: every texel's smoothstep
    /// is exactly 1. Random planes placed so the least value over the row, at a corner of its box,
    /// is within a metre to a micrometre of zero either way, where the rounding bound decides.
    #[test]
    fn a_skipped_plane_gives_every_texel_of_its_row_one() {
        let mut next = crate::stage::lines::tests::uniform(0x2545_f491);
        let (n, d0) = (64, 30.0f32);
        let x: Vec<f32> = (0..n).map(|i| i as f32 * d0).collect();
        let (mut skipped, mut kept) = (0, 0);
        for _ in 0..20_000 {
            let pn = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let mut row: Vec<f32> = (0..n).map(|_| 1000.0 + 800.0 * next()).collect();
            let (lo, hi) = row
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &h| {
                    (a.min(h), b.max(h))
                });
            // A texel at the corner of the row's box where the plane is least, so that the
            // rounding of its own value decides.
            let corner = if pn.x < 0.0 { n - 1 } else { 0 };
            row[corner] = if pn.z < 0.0 { hi } else { lo };
            let least = pn.x * x[corner] + pn.z * row[corner];
            let d = -least + (next() - 0.5) * 2.0 * 10f32.powi(-(next() * 6.0) as i32);
            let inv_margin = 1.0 / (50.0 + 100.0 * next());
            if row_inside(pn, d, x[n - 1], (lo, hi)) {
                skipped += 1;
                for i in 0..n {
                    let dist_p = pn.x * x[i] + pn.z * row[i] + d;
                    // The smoothstep is flat at 1 (it gives 1 down to about −4 mm here), so the
                    // sign is checked too: it is what the rounding allowance guarantees.
                    assert!(dist_p >= 0.0, "texel {i}: {dist_p}");
                    assert_eq!(smoothstep(dist_p * inv_margin + 1.0), 1.0, "texel {i}");
                }
            } else {
                kept += 1;
            }
        }
        assert!(
            skipped > 1000 && kept > 1000,
            "{skipped} skipped, {kept} kept"
        );
    }

    #[test]
    fn backface_is_one_on_front_and_silhouette_and_floors_behind() {
        assert_eq!(backface(0.8, 0.15), 1.0);
        assert_eq!(backface(-0.04, 0.15), 1.0);
        assert!((backface(-0.9, 0.15) - 0.15).abs() < 1e-6);
        let mid = backface(-0.2, 0.15);
        assert!(mid > 0.15 && mid < 1.0);
    }
}
