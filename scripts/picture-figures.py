#!/usr/bin/env python3
"""The picture figures on the bundled views (contrast, PSNR and SNR, the jagged edge), printed as
Markdown tables.

  python3 scripts/picture-figures.py --terrain target/release/terrain [--before OLD] [--size 256]

Per view: the terrain's luminance standard deviation (linear Rec. 709 luminance of the sRGB-decoded
image over the pixels whose positions hit ground: `render --json`'s terrain_luminance_std); PSNR
(dB) of the warped and GeoMipMap modes against the reference, as rendered by default, and SNR (the
reference's variance over the mean squared difference, dB: PSNR corrected for the picture's
contrast); and the jagged-edge
error: PSNR of each mesh mode, multisampled off and 4x, against the reference supersampled 4x.
With --before, the first two are also measured with another build (e.g. one from before the
picture features, commit 3418a4d) side by side. Needs numpy and Pillow.
"""
import argparse, os, subprocess, sys, tempfile
import numpy as np
from PIL import Image

VIEWS = ["jacksboro", "jacksboro-high", "gaussian", "gaussian-high", "hills", "hills-high"]


def render(binary, scene, mode, size, out, sets=()):
    png, npy = out + ".png", out + ".npy"
    cmd = [binary, "render", f"sketches/{scene}.toml", "--mode", mode, "-o", png,
           "--positions", npy, "--size", str(size)]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=np.float64)
    return rgb, np.load(npy)


def psnr(a, b):
    mse = np.mean((a - b) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


def snr(a, ref):
    """PSNR's contrast-aware sibling: the reference's own variance over the mean squared
    difference, in dB. A picture with 3x the contrast has 3x the differences for the same
    geometric error (PSNR 9.5 dB lower); its SNR is unchanged."""
    return 10 * np.log10(np.var(ref) / np.mean((a - ref) ** 2))


def luminance_std(rgb, pos):
    c = rgb / 255.0
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    y = lin @ np.array([0.2126, 0.7152, 0.0722])
    return y[pos[..., 3] > 0.5].std()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--terrain", default="target/release/terrain")
    ap.add_argument("--before")
    ap.add_argument("--size", type=int, default=256)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp()
    builds = [("now", a.terrain)] + ([("before", a.before)] if a.before else [])
    rows = {}
    for view in VIEWS:
        for name, binary in builds:
            f = lambda tag: os.path.join(tmp, f"{name}-{view}-{tag}")
            ref, _ = render(binary, view, "reference", a.size, f("ref"))
            w, wpos = render(binary, view, "warped", a.size, f("w"))
            g, _ = render(binary, view, "geomipmap", a.size, f("g"))
            rows[(view, name)] = (luminance_std(w, wpos), psnr(w, ref), psnr(g, ref),
                                  snr(w, ref), snr(g, ref))
        print(f"{view}: done", file=sys.stderr)
    head = "| view | " + " | ".join(
        f"{col} ({name})" for col in ["luminance std", "warped PSNR", "GeoMipMap PSNR",
                                      "warped SNR", "GeoMipMap SNR"] for name, _ in builds) + " |"
    print(head)
    print("|---" * (1 + 5 * len(builds)) + "|")
    for view in VIEWS:
        cells = [f"{rows[(view, name)][k]:.3f}" if k == 0 else f"{rows[(view, name)][k]:.2f}"
                 for k in range(5) for name, _ in builds]
        print(f"| {view} | " + " | ".join(cells) + " |")
    print()
    print("| view | warped, off | warped, 4x | GeoMipMap, off | GeoMipMap, 4x |")
    print("|---|---|---|---|---|")
    for view in VIEWS:
        f = lambda tag: os.path.join(tmp, f"aa-{view}-{tag}")
        ref, _ = render(a.terrain, view, "reference", a.size, f("ref"), ["render.msaa=4x"])
        cells = []
        for mode in ["warped", "geomipmap"]:
            for msaa in ["off", "4x"]:
                img, _ = render(a.terrain, view, mode, a.size, f(mode + msaa), [f"render.msaa={msaa}"])
                cells.append(f"{psnr(img, ref):.2f}")
        print(f"| {view} | " + " | ".join(cells) + " |")
        print(f"{view}: edges done", file=sys.stderr)


if __name__ == "__main__":
    main()
