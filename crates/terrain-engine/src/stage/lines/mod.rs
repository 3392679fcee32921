//! Line mappings: the one-dimensional warp that the row and column passes apply to every line
//! (`docs/design.md`, The warp): weights `w_i = (I_i + I_{i+1})/2`, positions `u` their running sum
//! scaled to `n−1`, output sample j interpolated inside the segment holding `u = j`. A mapping
//! gives the fractional source index of each output sample, monotone, 0 and n−1 at the ends.
//!
//! Rules:
//! - [`line_mapping`] maps one line; it is the reference and serves the guard's mean mapping.
//! - [`lane_mappings`] maps [`LANES`] lines at once, each lane bit-identical to
//!   [`line_mapping`]; the warp's passes use it. With AVX-512F or AVX2 it runs as intrinsics
//!   (`x86`), otherwise as plain Rust (`portable`).
//! - [`row_samples`] and [`column_points`] are the warp's two interpolation loops over a group of
//!   whole lines as one AVX-512 kernel each, lane for lane [`lerp_lanes`]'s operations; without
//!   AVX-512F they decline and the caller's loop runs.
//! - Non-finite or negative importance counts as 0; a line with no weight stays put.
//!
//! Why lanes across lines: a line's running sum is a chain of dependent additions, one per
//! sample, that no vector width shortens, and finding each output's segment is a data-dependent
//! load. Side by side, eight lines share each step of the chain and each lookup is one gather
//! (with AVX2) or one carried pair (with AVX-512: `x86::mappings_avx512`). Eight lanes as plain
//! Rust are no faster than one line at a time: LLVM leaves the lookups scalar (docs/decisions.md,
//! “Warp in lanes of eight”).
//!
//! Why intrinsics and not a SIMD crate: what pays here is the lookup by lane, a gather or a
//! scatter of single lanes. `wide` has neither, and lanes without them are no faster (above). A
//! dispatching crate such as `pulp` would take over
//! the run-time choice of instruction set, which is a few lines here (as in the importance), but
//! not the gathers' raw pointers, so the kernel would stay `unsafe` either way.

/// Scratch for [`line_mapping`], sized for one line.
#[derive(Clone, Debug)]
pub struct LineScratch {
    u: Vec<f64>,
    segment: Vec<u32>,
}

impl LineScratch {
    pub fn new(n: usize) -> LineScratch {
        LineScratch {
            u: vec![0.0; n],
            segment: vec![0; n],
        }
    }
}

/// Fractional source index of each output sample of one line with importance `imp` (its length
/// is the line's). Non-finite or negative importance counts as 0; a line with no weight stays put.
///
/// Branch-free: each segment scatters a mark at its first output, a running sum of the marks is
/// then every output's segment. A search that walks the segments mispredicts once per segment.
#[inline(always)]
pub fn line_mapping(imp: &[f32], scratch: &mut LineScratch, out: &mut [f64]) {
    let n = out.len();
    let LineScratch { u, segment } = scratch;
    u[0] = 0.0;
    let mut prev = weight(imp[0]);
    for i in 0..n - 1 {
        let next = weight(imp[i + 1]);
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
    let to_output = (n - 1) as f64 / total;
    let step = total / (n - 1) as f64;
    segment.fill(0);
    for &ui in &u[1..n - 1] {
        // The first output at or after u_i (x ≥ 0, so the cast is floor and this is ceil).
        let x = ui * to_output;
        let floor = x as usize;
        let first = (floor + usize::from((floor as f64) < x)).min(n - 1);
        segment[first] += 1;
    }
    let mut seg = 0u32;
    for (j, o) in out.iter_mut().enumerate() {
        seg += segment[j];
        let i = seg as usize;
        let width = u[i + 1] - u[i];
        let f = if width > 0.0 {
            (j as f64 * step - u[i]) / width
        } else {
            0.0
        };
        *o = i as f64 + f.clamp(0.0, 1.0);
    }
    out[0] = 0.0;
    out[n - 1] = (n - 1) as f64;
}

/// A sample's weight in the running sum: its importance where finite and positive, else 0.
#[inline(always)]
fn weight(v: f32) -> f64 {
    if v.is_finite() && v > 0.0 {
        v as f64
    } else {
        0.0
    }
}

/// Lines mapped together by [`lane_mappings`], one per SIMD lane (f64: one AVX-512 register,
/// two AVX2 ones).
pub const LANES: usize = 8;

/// Scratch for [`lane_mappings`], sized for lines of one length.
#[derive(Clone, Debug)]
pub struct LaneScratch {
    u: Vec<[f64; LANES]>,
    start: Vec<[u32; LANES]>,
    /// The AVX-512 kernel's `(u_i, u_{i+1})` of the last segment starting at each output; empty
    /// where the processor lacks AVX-512F.
    ends_u: Vec<[[f64; 2]; LANES]>,
}

impl LaneScratch {
    pub fn new(n: usize) -> LaneScratch {
        LaneScratch {
            u: vec![[0.0; LANES]; n],
            start: vec![[0; LANES]; n],
            ends_u: if crate::stage::simd::avx512() {
                vec![[[0.0; 2]; LANES]; n]
            } else {
                Vec::new()
            },
        }
    }
}

/// [`line_mapping`] of [`LANES`] lines at once: `imp[i][l]` is line l's importance at i and
/// `out[j][l]` its mapping. Each lane's result is bit-identical to [`line_mapping`]'s: the same
/// operations in the same order (why lanes across lines: the module doc).
///
/// The segment search is the running maximum of the last segment starting at each output (the
/// count of [`line_mapping`]'s marks, since the first outputs of the segments never decrease),
/// so the scatter is a plain store per lane and not a read-modify-write.
#[inline(always)]
pub fn lane_mappings(imp: &[[f32; LANES]], scratch: &mut LaneScratch, out: &mut [[f64; LANES]]) {
    let n = out.len();
    assert!(
        n >= 2 && imp.len() >= n && scratch.u.len() >= n && scratch.start.len() >= n,
        "lines of {n} samples"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() && n <= i32::MAX as usize / LANES {
        assert!(scratch.ends_u.len() >= n, "lines of {n} samples");
        // SAFETY: the processor has AVX-512F and AVX2 and the lines' indices fit an i32,
        // checked just above; the lengths, just before and above.
        unsafe { x86::mappings_avx512(imp, scratch, out) };
        ends(&scratch.u[n - 1], out);
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx2() && n <= i32::MAX as usize / LANES {
        // SAFETY: the processor has AVX2 and the lines' indices fit an i32, checked just
        // above; the lengths, just before.
        unsafe { x86::mappings(imp, scratch, out) };
        ends(&scratch.u[n - 1], out);
        return;
    }
    portable(imp, scratch, out);
    ends(&scratch.u[n - 1], out);
}

/// [`lane_mappings`] without SIMD intrinsics, for processors without AVX2 (and as the record of
/// what the AVX2 kernel computes). Leaves the ends to [`ends`].
#[inline(always)]
fn portable(imp: &[[f32; LANES]], scratch: &mut LaneScratch, out: &mut [[f64; LANES]]) {
    let n = out.len();
    let LaneScratch { u, start, .. } = scratch;
    let (u, start) = (&mut u[..n], &mut start[..n]);
    u[0] = [0.0; LANES];
    let mut prev = imp[0].map(weight);
    for i in 0..n - 1 {
        let next = imp[i + 1].map(weight);
        for l in 0..LANES {
            u[i + 1][l] = u[i][l] + 0.5 * (prev[l] + next[l]);
        }
        prev = next;
    }
    let total = u[n - 1];
    let last = (n - 1) as f64;
    let to_output = total.map(|t| last / t);
    let step = total.map(|t| t / last);
    start.fill([0; LANES]);
    for (i, ui) in u.iter().enumerate().take(n - 1).skip(1) {
        for l in 0..LANES {
            // The first output at or after u_i, as line_mapping's marks have it; the min also
            // keeps a lane with no weight (NaN, infinity) inside the line until it is reset.
            // x lies in [0, n − 1], so the cast is floor and this is ceil.
            let x = (ui[l] * to_output[l]).min(last);
            let floor = x as usize;
            let first = floor + usize::from((floor as f64) < x);
            start[first.min(n - 1)][l] = i as u32;
        }
    }
    let mut seg = [0u32; LANES];
    for (j, o) in out.iter_mut().enumerate() {
        for l in 0..LANES {
            seg[l] = seg[l].max(start[j][l]);
            let i = (seg[l] as usize).min(n - 2);
            let width = u[i + 1][l] - u[i][l];
            let f = if width > 0.0 {
                (j as f64 * step[l] - u[i][l]) / width
            } else {
                0.0
            };
            o[l] = i as f64 + f.clamp(0.0, 1.0);
        }
    }
}

/// Where each lane's line starts in a buffer of lines of `n` samples (line `first + l`; lines
/// past the last repeat it), for [`lerp_lanes`]. Worked out once for a group of lines and used
/// at each of its samples, so that its division (`values.len() / n`) and eight products stay out
/// of the warp's interpolation loops.
#[derive(Clone, Copy, Debug)]
pub struct LaneLines {
    len: usize,
    n: usize,
    start: [usize; LANES],
    /// `start` as the gathers' indices; used only where `len` fits an i32.
    start32: [i32; LANES],
}

impl LaneLines {
    /// Lines `first ..` of `values`, lines of `n ≥ 2` samples.
    #[inline(always)]
    pub fn new(values: &[f32], n: usize, first: usize) -> LaneLines {
        assert!(n >= 2 && values.len() >= n, "lines of {n} samples");
        let lines = values.len() / n;
        let start: [usize; LANES] = std::array::from_fn(|l| (first + l).min(lines - 1) * n);
        LaneLines {
            len: values.len(),
            n,
            start,
            start32: start.map(|s| s as i32),
        }
    }
}

/// Lane l's value of its line of `lines` ([`LaneLines`], made for `values`) linearly
/// interpolated at fractional index `a[l]`: what [`line_mapping`]'s callers do with each
/// mapping, for [`LANES`] lines at once.
#[inline(always)]
pub fn lerp_lanes(values: &[f32], lines: &LaneLines, a: &[f64; LANES]) -> [f32; LANES] {
    assert_eq!(values.len(), lines.len, "the lines' buffer");
    #[cfg(target_arch = "x86_64")]
    if values.len() < i32::MAX as usize {
        if crate::stage::simd::avx512() {
            // SAFETY: the processor has AVX-512F and AVX2 and the indices fit an i32, checked
            // just above; every lane's line lies whole in `values` (`LaneLines::new`, made for
            // a buffer of this length).
            return unsafe { x86::lerp_avx512(values, lines, a) };
        }
        if crate::stage::simd::avx2() {
            // SAFETY: as above, with AVX2.
            return unsafe { x86::lerp(values, lines, a) };
        }
    }
    std::array::from_fn(|l| lerp_at(&values[lines.start[l]..][..lines.n], a[l]))
}

/// The row pass's loop over [`LANES`] whole lines `first ..` of `values` (`lines`, made for
/// it): for each output s, lane l's `(a·d0) as f32` to `x[s·n + first + l]` and its line
/// interpolated at a ([`lerp_lanes`]) to `v[s·n + first + l]`, a = `maps[s][l]`. One AVX-512
/// kernel, so that the loop carries no dispatch, bounds checks or copies through the stack; false,
/// having done nothing, where the processor lacks AVX-512F (the caller's loop then does it, the
/// same bits).
#[inline(always)]
pub fn row_samples(
    values: &[f32],
    lines: &LaneLines,
    maps: &[[f64; LANES]],
    d0: f32,
    x: &mut [f32],
    v: &mut [f32],
    first: usize,
) -> bool {
    let n = lines.n;
    assert!(
        values.len() == lines.len
            && first + LANES <= n
            && x.len() >= maps.len() * n
            && v.len() >= maps.len() * n,
        "the row pass's lines"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() && values.len() < i32::MAX as usize {
        // SAFETY: the processor has AVX-512F and AVX2 and the indices fit an i32, checked just
        // above; the bounds, just before.
        unsafe { x86::row_samples(values, lines, maps, d0 as f64, x, v, first) };
        return true;
    }
    false
}

/// The column pass's loop over [`LANES`] whole columns `s0 ..`, whose row-warped x are lines
/// of `row_x` (`lines`, made for it): for each output t, point `s0 + l` of Φ's row t is lane
/// l's line interpolated at b ([`lerp_lanes`]) and `(b·d0) as f32`, b = `maps[t][l]`. As
/// [`row_samples`]: one AVX-512 kernel, or false, having done nothing.
#[inline(always)]
pub fn column_points(
    row_x: &[f32],
    lines: &LaneLines,
    maps: &[[f64; LANES]],
    d0: f32,
    phi: &mut [[f32; 2]],
    s0: usize,
) -> bool {
    let n = lines.n;
    assert!(
        row_x.len() == lines.len && s0 + LANES <= n && phi.len() >= maps.len() * n,
        "the column pass's lines"
    );
    #[cfg(target_arch = "x86_64")]
    if crate::stage::simd::avx512() && row_x.len() < i32::MAX as usize {
        // SAFETY: as in `row_samples`.
        unsafe { x86::column_points(row_x, lines, maps, d0 as f64, phi, s0) };
        return true;
    }
    false
}

/// `values` linearly interpolated at fractional index `a` (a mapping's, in [0, len − 1]; outside
/// it the end segments extend, and NaN gives NaN).
#[inline(always)]
pub fn lerp_at(values: &[f32], a: f64) -> f32 {
    let (i, f) = lerp_weight(a, values.len());
    values[i] + (values[i + 1] - values[i]) * f
}

/// The segment and the weight of its upper end that [`lerp_at`] takes at `a` on a line of `len`
/// samples, for callers that interpolate several lines at one `a`.
#[inline(always)]
pub fn lerp_weight(a: f64, len: usize) -> (usize, f32) {
    // The cast is floor for a ≥ 0 and saturates below (0) and above.
    let i = (a as usize).min(len - 2);
    (i, (a - i as f64) as f32)
}

/// The ends of each lane's mapping: 0 and n − 1 exactly, or the identity for a line with no
/// weight (all zero, or a sum that is not finite), which stays put.
fn ends(total: &[f64; LANES], out: &mut [[f64; LANES]]) {
    let last = (out.len() - 1) as f64;
    for (l, &t) in total.iter().enumerate() {
        if t > 0.0 && t.is_finite() {
            out[0][l] = 0.0;
            out[out.len() - 1][l] = last;
        } else {
            for (j, o) in out.iter_mut().enumerate() {
                o[l] = j as f64;
            }
        }
    }
}

/// [`portable`] in x86 intrinsics. With AVX2 (`mappings`), four f64 lanes to a register, the two
/// halves of the eight interleaved so that their chains of additions overlap; with AVX-512F
/// (`mappings_avx512`), the eight in one register and each segment's ends scattered beside its
/// index instead of gathered per output. The same operations in the same order (no fused
/// multiply-adds; `ceil` for line_mapping's floor-and-compare, equal on x ≥ 0), so the
/// results are bit-identical, which `tests` checks.
///
/// Why intrinsics: LLVM unrolls the lane loops of [`portable`] and then leaves the segment
/// lookup scalar, for want of gathers, no faster than eight calls of [`line_mapping`].
#[cfg(target_arch = "x86_64")]
mod x86;

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Lines of every kind the stage meets: importance over twelve orders of magnitude, zero
    /// runs, NaN and infinity, all zero, one spike.
    fn lines(n: usize) -> Vec<[f32; LANES]> {
        let mut rnd = uniform(0x9e37_79b9);
        (0..n)
            .map(|i| {
                let mut v: [f32; LANES] = std::array::from_fn(|_| 10f32.powf(12.0 * rnd() - 6.0));
                v[1] = if i % 7 < 3 { 0.0 } else { v[1] };
                v[2] = [f32::NAN, f32::INFINITY, -1.0, 2.0][i % 4];
                v[3] = 0.0;
                v[4] = if i == n / 3 { 1e30 } else { 1e-30 };
                v[5] = 1.0;
                v
            })
            .collect()
    }

    /// Numbers in [0, 1] from a seed (xorshift32; 0 is taken as 1), for the stage's tests.
    pub(crate) fn uniform(seed: u32) -> impl FnMut() -> f32 {
        let mut x = seed.max(1);
        move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        }
    }

    /// One line's mapping, with a scratch of its own.
    pub(crate) fn mapping(imp: &[f32]) -> Vec<f64> {
        let mut out = vec![0.0; imp.len()];
        line_mapping(imp, &mut LineScratch::new(imp.len()), &mut out);
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
    fn lerp_lanes_equals_lerp_at_bit_for_bit() {
        let n = 19;
        // Three whole lines and part of a fourth, which no lane reads.
        let values: Vec<f32> = (0..3 * n + 5)
            .map(|i| ((i * 37) % 23) as f32 * 1.7 - 9.0)
            .collect();
        let inside = [0.0, 0.3, 5.5, 17.99, 18.0, 7.25, 1.0, 12.5];
        // Outside a mapping's range: the end segments extend, NaN stays NaN, nothing is read
        // outside the lane's line.
        let outside = [
            -0.5,
            -3.0,
            18.5,
            1e12,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            3e9,
        ];
        for a in [inside, outside] {
            for first in 0..4 {
                // Every build the processor can run, each called directly.
                let lines = LaneLines::new(&values, n, first);
                let mut builds = vec![lerp_lanes(&values, &lines, &a)];
                #[cfg(target_arch = "x86_64")]
                {
                    use crate::stage::simd;
                    if simd::avx2() {
                        // SAFETY: the processor has AVX2; `values` holds whole lines.
                        builds.push(unsafe { x86::lerp(&values, &lines, &a) });
                    }
                    if simd::avx512() {
                        // SAFETY: as above, with AVX-512F.
                        builds.push(unsafe { x86::lerp_avx512(&values, &lines, &a) });
                    }
                }
                for l in 0..LANES {
                    // Lines past the last repeat it.
                    let want = lerp_at(&values[(first + l).min(2) * n..][..n], a[l]);
                    let at = format!("line {first}+{l} at {}", a[l]);
                    for got in &builds {
                        assert_eq!(got[l].is_nan(), want.is_nan(), "{at}");
                        if !want.is_nan() {
                            assert_eq!(got[l].to_bits(), want.to_bits(), "{at}");
                        }
                    }
                }
            }
        }
    }

    /// The passes' kernels give `lerp_at`'s bits for every lane and sample, at mappings inside
    /// a line and outside it (NaN too), and the coordinates' `(a·d0) as f32`.
    #[test]
    fn the_pass_kernels_equal_lerp_at_bit_for_bit() {
        let (n, count, first, d0) = (19, 12, 3, 2.5f32);
        let values: Vec<f32> = (0..count * n)
            .map(|i| ((i * 37) % 23) as f32 * 1.7 - 9.0)
            .collect();
        let maps: Vec<[f64; LANES]> = (0..n)
            .map(|k| {
                std::array::from_fn(|l| match (k + l) % 6 {
                    0 => k as f64 * 0.93,
                    1 => -0.5 - k as f64,
                    2 => 17.99 + k as f64,
                    3 => f64::NAN,
                    4 => 18.0,
                    _ => (k * l) as f64 * 0.37,
                })
            })
            .collect();
        let lines = LaneLines::new(&values, n, first);
        let (mut x, mut v) = (vec![0.0; n * n], vec![0.0; n * n]);
        let mut phi = vec![[0.0; 2]; n * n];
        let rows = row_samples(&values, &lines, &maps, d0, &mut x, &mut v, first);
        let columns = column_points(&values, &lines, &maps, d0, &mut phi, first);
        assert_eq!((rows, columns), (crate::stage::simd::avx512(), rows));
        if !rows {
            eprintln!("skipped: the kernels need AVX-512F, which this processor lacks");
            return;
        }
        let same = |got: f32, want: f32, at: &str| {
            assert_eq!(got.is_nan(), want.is_nan(), "{at}");
            if !want.is_nan() {
                assert_eq!(got.to_bits(), want.to_bits(), "{at}");
            }
        };
        for (k, a) in maps.iter().enumerate() {
            for l in 0..LANES {
                let value = lerp_at(&values[(first + l) * n..][..n], a[l]);
                let coordinate = (a[l] * d0 as f64) as f32;
                let at = format!("output {k} lane {l} at {}", a[l]);
                same(v[k * n + first + l], value, &at);
                same(x[k * n + first + l], coordinate, &at);
                same(phi[k * n + first + l][0], value, &at);
                same(phi[k * n + first + l][1], coordinate, &at);
            }
        }
    }

    #[test]
    fn lanes_equal_line_mapping_bit_for_bit() {
        // One scratch for every length, larger than most, used twice for each: what a line
        // leaves behind must not reach the next.
        let mut scratch = LaneScratch::new(129);
        for n in [2, 3, 17, 128, 129] {
            let mut lanes = vec![[0.0; LANES]; n];
            let mut before: Vec<[f32; LANES]> = lines(n);
            before.reverse();
            lane_mappings(&before, &mut scratch, &mut lanes);
            let imp = lines(n);
            lane_mappings(&imp, &mut scratch, &mut lanes);
            let mut plain = vec![[0.0; LANES]; n];
            portable(&before, &mut scratch, &mut plain);
            portable(&imp, &mut scratch, &mut plain);
            ends(&scratch.u[n - 1], &mut plain);
            // Each kernel the processor can run, called directly, after the other lines.
            let mut kernels = vec![];
            #[cfg(target_arch = "x86_64")]
            {
                use crate::stage::simd;
                type Kernel = unsafe fn(&[[f32; LANES]], &mut LaneScratch, &mut [[f64; LANES]]);
                let runnable: [(&str, bool, Kernel); 2] = [
                    ("AVX2", simd::avx2(), x86::mappings),
                    ("AVX-512", simd::avx512(), x86::mappings_avx512),
                ];
                for (name, runs, kernel) in runnable {
                    if !runs {
                        eprintln!("skipped: the processor cannot run the {name} kernel");
                        continue;
                    }
                    let mut out = vec![[0.0; LANES]; n];
                    // SAFETY: the processor runs this kernel; every buffer holds n samples.
                    unsafe { kernel(&before, &mut scratch, &mut out) };
                    unsafe { kernel(&imp, &mut scratch, &mut out) };
                    ends(&scratch.u[n - 1], &mut out);
                    kernels.push((name, out));
                }
            }
            let mut one = LineScratch::new(n);
            for l in 0..LANES {
                let line: Vec<f32> = imp.iter().map(|v| v[l]).collect();
                let mut want = vec![0.0; n];
                line_mapping(&line, &mut one, &mut want);
                for j in 0..n {
                    let at = format!("n {n} lane {l} j {j}");
                    assert_eq!(lanes[j][l].to_bits(), want[j].to_bits(), "{at}");
                    assert_eq!(plain[j][l].to_bits(), want[j].to_bits(), "{at}");
                    for (name, out) in &kernels {
                        assert_eq!(out[j][l].to_bits(), want[j].to_bits(), "{name} {at}");
                    }
                }
            }
        }
    }
}
