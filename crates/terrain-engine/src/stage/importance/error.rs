//! The geometric-error term: the detail's curvature by octave level, the sketch's curvature the
//! map holds (`sketch_curvature`) and the one it cannot see (`SubTexel`). Each row helper is
//! `#[inline(always)]`, so that it is built into the row loops' AVX-512 and AVX2 builds
//! (`rows`); what the loops read is `pub(super)`, the rest private.

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
    pub(super) water_m: f32,
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
pub(super) struct SubTexel {
    /// (start, end, inv_width, delta) in o, one per segment.
    segments: [[f32; 4]; SUB_TEXEL_SEGMENTS],
    pub(super) count: usize,
}

impl SubTexel {
    pub(super) const NONE: SubTexel = SubTexel {
        segments: [[0.0; 4]; SUB_TEXEL_SEGMENTS],
        count: 0,
    };

    /// Adds the curvature to `out` for the row's octave levels `octave`, whose least and
    /// greatest are `(lo, hi)`: a pass over the row for each segment the row's levels cross, a
    /// constant for the segments they all lie beyond.
    #[inline(always)]
    pub(super) fn add_row(&self, (lo, hi): (f32, f32), octave: &[f32], out: &mut [f32]) {
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
    pub(super) fn sub_texel(&self, d0: f64) -> SubTexel {
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
    pub(super) fn add_curvature_row(&self, range: (f32, f32), octave: &[f32], out: &mut [f32]) {
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
pub(super) fn octave_range(octave: &[f32]) -> (f32, f32) {
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

/// The largest second derivative of the sketch map's heights along a row (1/m): |h_xx|, |h_yy|
/// and |h_xy| from the rows `down` and `up` `rows_apart` rows apart around it (1 at the map's
/// edge, where one of them is the row itself and `h_yy` is taken as 0), one-sided at the ends.
// The loop indexes each texel's neighbours; an iterator over `out` would hide them.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(super) fn sketch_curvature(
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

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use glam::DVec2;

    /// The bundled scenes' detail (8 m, gain 0.45) at the default bias, over `d_atlas`.
    pub(in crate::stage::importance) fn bundled_detail(
        d_atlas: f64,
        lattice_origin_m: DVec2,
    ) -> crate::detail::Detail {
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
}
