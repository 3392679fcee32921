//! The importance map's row loops: one body (`rows`, `#[inline(always)]`), built for AVX-512,
//! AVX2 and the baseline and chosen at run time (`update_rows`), then the floor. The builds run
//! the same operations in the same order, so give the same bits.

use super::error::{SubTexel, octave_range, sketch_curvature};
use super::view::{
    MARGIN_SHARE, backface, fill_on_atlas, on_atlas, row_inside, slope_x, smoothstep,
};
use super::{ImportanceMap, ImportanceParams};
use crate::camera::Camera;
use crate::stage::sketch_map::{SketchMap, Turn};
use glam::{DVec2, DVec3};

impl ImportanceMap {
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
        self.rows::<0>(map, atlas_bounds, camera, surface_max, p, row_step);
    }

    /// [`ImportanceMap::rows`] compiled for AVX-512's sixteen f32 lanes: the same loops in
    /// registers twice as wide, with a copy for maps of side 128. The same operations in the same
    /// order: the same bits.
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
        if map.n == 128 {
            self.rows::<128>(map, atlas_bounds, camera, surface_max, p, row_step);
        } else {
            self.rows::<0>(map, atlas_bounds, camera, surface_max, p, row_step);
        }
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
        self.rows::<0>(map, atlas_bounds, camera, surface_max, p, row_step);
    }

    /// The map's rows for a map of side `N`, or of any side where `N` is 0 (the module doc's
    /// copy for the default side).
    // The row loops index five parallel slices by column; zipped iterators would hide that.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn rows<const N: usize>(
        &mut self,
        map: &SketchMap,
        atlas_bounds: (DVec2, DVec2),
        camera: &Camera,
        surface_max: Option<&[f32]>,
        p: &ImportanceParams,
        row_step: usize,
    ) {
        let n = if N == 0 { map.n } else { N };
        assert_eq!(n, map.n, "the map's side");
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stage::importance::ErrorTerm;
    use crate::stage::importance::error::tests::bundled_detail;

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
            baseline.rows::<0>(&map, bounds, &camera, None, &p, 1);
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
}
