//! The image metrics against their reference implementations: PSNR and SSIM against
//! scikit-image, FLIP against NVIDIA's flip-evaluator, on the committed image pairs in
//! `tests/metrics/` (renders of the bundled scenes at 64×48, and a synthetic noise pair). The
//! values were computed once by `tests/metrics/reference_values.py` (its doc gives each call and
//! version) into `reference_values.json`.
//!
//! Agreement asked: 0.01 dB for PSNR, 1e-3 for SSIM and FLIP's mean.

mod common;
use common::*;
use terrain_cli::eval::metrics;

#[derive(serde::Deserialize)]
struct Values {
    pairs: Vec<Pair>,
}

#[derive(serde::Deserialize)]
struct Pair {
    reference: String,
    test: String,
    psnr_db: f64,
    ssim: f64,
    flip_mean: f64,
}

fn image(name: &str) -> (u32, Vec<u8>) {
    let path = manifest_dir().join("tests/metrics").join(name);
    let (w, _, rgba) = read_png(&path).unwrap_or_else(|| panic!("{}", path.display()));
    (w, rgba)
}

#[test]
fn metrics_agree_with_their_reference_implementations() {
    let text = std::fs::read_to_string(manifest_dir().join("tests/metrics/reference_values.json"))
        .unwrap();
    let values: Values = serde_json::from_str(&text).unwrap();
    assert_eq!(values.pairs.len(), 4);
    for p in &values.pairs {
        let (w, reference) = image(&p.reference);
        let (_, test) = image(&p.test);
        let what = format!("{} against {}", p.test, p.reference);
        let psnr = metrics::psnr(&reference, &test);
        let ssim = metrics::ssim(&reference, &test, w).unwrap();
        let flip = metrics::flip_mean(&reference, &test, w).unwrap();
        println!(
            "{what}: PSNR {psnr:.4} dB (scikit-image {:.4}), SSIM {ssim:.5} ({:.5}), FLIP {flip:.5} ({:.5})",
            p.psnr_db, p.ssim, p.flip_mean
        );
        assert!(
            (psnr - p.psnr_db).abs() < 0.01,
            "{what}: PSNR {psnr} vs {}",
            p.psnr_db
        );
        assert!(
            (ssim - p.ssim).abs() < 1e-3,
            "{what}: SSIM {ssim} vs {}",
            p.ssim
        );
        assert!(
            (flip - p.flip_mean).abs() < 1e-3,
            "{what}: FLIP {flip} vs {}",
            p.flip_mean
        );
    }
}

#[test]
fn identical_images_score_perfectly_on_every_metric() {
    let (w, a) = image("jacksboro-reference.png");
    assert_eq!(metrics::psnr(&a, &a), f64::INFINITY);
    assert_eq!(metrics::ssim(&a, &a, w), Some(1.0));
    assert_eq!(metrics::flip_mean(&a, &a, w), Some(0.0));
}
