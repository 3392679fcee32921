#!/usr/bin/env python3
"""Reference values of the image metrics `terrain compare` reports, computed once with their
reference implementations on the committed image pairs beside this script, into
`reference_values.json`, which `tests/metrics.rs` checks the Rust metrics against.

    pip install scikit-image==0.26.0 flip-evaluator==1.7
    python3 tests/metrics/reference_values.py

- PSNR: scikit-image's peak_signal_noise_ratio over the RGB values, data_range=255.
- SSIM: scikit-image's structural_similarity as Wang et al. (2004) define it (11×11 Gaussian
  window, sigma 1.5, K1 0.01, K2 0.03, population covariances, data_range 255) on Rec. 709 luma of
  the sRGB values, 0.2126 R + 0.7152 G + 0.0722 B, in float64.
- FLIP: NVIDIA's flip-evaluator, LDR, sRGB inputs, 67.0206 pixels per degree (its default: a 0.7 m
  wide 3840-pixel display seen from 0.7 m), mean over the error map.

The synthetic pair (noise-a, noise-b: noise and a blurred, brightened copy) is written by this
script when missing, from a fixed seed.
"""

import json
import pathlib

import flip_evaluator
import numpy as np
from PIL import Image
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

HERE = pathlib.Path(__file__).resolve().parent
PAIRS = [
    ("jacksboro-reference.png", "jacksboro-warped-mesh64.png"),
    ("jacksboro-reference.png", "jacksboro-geomipmap-tau8.png"),
    ("hills-reference.png", "hills-warped-mesh32.png"),
    ("noise-a.png", "noise-b.png"),
]
PPD = 0.7 * (3840 / 0.7) * np.pi / 180


def synthetic():
    a, b = HERE / "noise-a.png", HERE / "noise-b.png"
    if a.exists() and b.exists():
        return
    rng = np.random.default_rng(17)
    x = rng.integers(0, 256, size=(40, 56, 3)).astype(np.float64)
    # A 3-tap box blur along rows and a +12 offset: structure kept in part, luminance moved.
    y = (np.roll(x, 1, axis=1) + x + np.roll(x, -1, axis=1)) / 3 + 12
    for path, v in ((a, x), (b, np.clip(np.rint(y), 0, 255))):
        Image.fromarray(v.astype(np.uint8), "RGB").convert("RGBA").save(path)


def rgb(name):
    return np.asarray(Image.open(HERE / name).convert("RGB"))


def luma(image):
    f = image.astype(np.float64)
    return 0.2126 * f[..., 0] + 0.7152 * f[..., 1] + 0.0722 * f[..., 2]


def main():
    synthetic()
    values = []
    for ref_name, test_name in PAIRS:
        ref, test = rgb(ref_name), rgb(test_name)
        psnr = peak_signal_noise_ratio(ref, test, data_range=255)
        ssim = structural_similarity(
            luma(ref),
            luma(test),
            data_range=255,
            gaussian_weights=True,
            sigma=1.5,
            use_sample_covariance=False,
        )
        _, flip, _ = flip_evaluator.evaluate(
            ref.astype(np.float32) / 255,
            test.astype(np.float32) / 255,
            "LDR",
            applyMagma=False,
            parameters={"ppd": PPD},
        )
        values.append(
            {
                "reference": ref_name,
                "test": test_name,
                "psnr_db": float(psnr),
                "ssim": float(ssim),
                "flip_mean": float(flip),
            }
        )
    out = {
        "made_with": "scikit-image 0.26.0 (PSNR, SSIM), flip-evaluator 1.7 (FLIP)",
        "pairs": values,
    }
    (HERE / "reference_values.json").write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
