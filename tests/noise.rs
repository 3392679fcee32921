//! The procedural detail's noise: each octave's spectrum peaks at its frequency f_k and is
//! band-limited around it; values agree 10,000 km away with the lattice shifted (see also the unit
//! tests in `src/detail.rs`).

use glam::DVec2;
use terrain_engine::Detail;

fn detail() -> Detail {
    Detail {
        octaves: 8,
        amplitude_m: 1.0,
        gain: 0.5,
        seed: 11,
        bias: 0.0,
        d_atlas: 8.0,
        lattice_origin_m: DVec2::ZERO,
    }
}

/// Energy of octave k per radial frequency bin (width 1/(N·h)), from a separable DFT of an N²
/// patch sampled every h metres, summed over `patches` patches.
fn radial_energy(d: &Detail, k: u32, n: usize, h: f64, patches: usize) -> Vec<f64> {
    let mut rings = vec![0.0; n];
    let tau = std::f64::consts::TAU;
    for patch in 0..patches {
        let corner = DVec2::new(1000.0 + 517.3 * patch as f64, -300.0 + 211.9 * patch as f64);
        let field: Vec<f64> = (0..n * n)
            .map(|q| {
                d.octave_world(k, corner + DVec2::new((q % n) as f64, (q / n) as f64) * h)
                    .0 as f64
            })
            .collect();
        // Rows, then columns: O(N³) instead of O(N⁴).
        let dft_1d = |input: &[(f64, f64)], out: &mut [(f64, f64)]| {
            for (f, o) in out.iter_mut().enumerate() {
                let (mut re, mut im) = (0.0, 0.0);
                for (x, &(a, b)) in input.iter().enumerate() {
                    let (s, c) = (tau * (f * x) as f64 / n as f64).sin_cos();
                    re += a * c + b * s;
                    im += b * c - a * s;
                }
                *o = (re, im);
            }
        };
        let mut rows = vec![(0.0, 0.0); n * n];
        for j in 0..n {
            let line: Vec<(f64, f64)> = field[j * n..(j + 1) * n]
                .iter()
                .map(|&v| (v, 0.0))
                .collect();
            dft_1d(&line, &mut rows[j * n..(j + 1) * n]);
        }
        let mut col_out = vec![(0.0, 0.0); n];
        for i in 0..n {
            let col: Vec<(f64, f64)> = (0..n).map(|j| rows[j * n + i]).collect();
            dft_1d(&col, &mut col_out);
            for (j, &(re, im)) in col_out.iter().enumerate() {
                let fx = if i <= n / 2 {
                    i as f64
                } else {
                    i as f64 - n as f64
                };
                let fy = if j <= n / 2 {
                    j as f64
                } else {
                    j as f64 - n as f64
                };
                let r = (fx * fx + fy * fy).sqrt().round() as usize;
                if r < n {
                    rings[r] += re * re + im * im;
                }
            }
        }
    }
    rings
}

#[test]
fn octave_spectrum_peaks_at_its_frequency_and_is_band_limited() {
    let d = detail();
    for k in [2u32, 4] {
        let f_k = d.frequency(k);
        let n = 96;
        // 12 cycles of f_k across the patch: bin 12 is f_k, Nyquist (bin 48) is 4·f_k.
        let h = 12.0 / (n as f64 * f_k);
        let rings = radial_energy(&d, k, n, h, 6);
        let bin_of = |f: f64| f * n as f64 * h;
        // The peak of the spectrum smoothed over three bins: one bin alone is a noisy estimate.
        let smooth = |b: usize| rings[b - 1] + rings[b] + rings[b + 1];
        let peak = (2..n / 2 - 1)
            .max_by(|&a, &b| smooth(a).total_cmp(&smooth(b)))
            .unwrap();
        let peak_f = peak as f64 / (n as f64 * h);
        eprintln!(
            "octave {k}: f_k {f_k:.4}, peak {peak_f:.4} ({:.2} f_k)",
            peak_f / f_k
        );
        let total: f64 = rings[1..n / 2].iter().sum();
        let band: f64 = rings
            [bin_of(0.5 * f_k).ceil() as usize..=bin_of(2.0 * f_k).floor() as usize]
            .iter()
            .sum();
        eprintln!(
            "  energy within [f_k/2, 2 f_k]: {:.1} %",
            100.0 * band / total
        );
        assert!(
            peak_f > 0.8 * f_k && peak_f < 1.25 * f_k,
            "octave {k} peaks at {:.2} f_k",
            peak_f / f_k
        );
        assert!(
            band / total > 0.8,
            "octave {k}: only {:.1} % of its energy in [f_k/2, 2 f_k]",
            100.0 * band / total
        );
    }
}
