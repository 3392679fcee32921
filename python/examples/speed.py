"""Python against `terrain batch`, side by side in one run: the same N random snapshots of a
scene, rendered by `renderer.render` and by `terrain batch` (jobs file `[random]` with the same
seed, so the same cameras); medians of the per-snapshot seconds.

    python python/examples/speed.py sketches/jacksboro.toml --terrain target/release/terrain

`batch`'s seconds per item (its manifest's `seconds`) include encoding and writing the PNG;
Python's include copying the picture into a NumPy array. Both keep one renderer for all items.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import tempfile
import time

import terrain


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--terrain", default="terrain", help="the terrain binary")
    ap.add_argument("-n", type=int, default=100)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    scene_path = pathlib.Path(a.scene).resolve()

    with tempfile.TemporaryDirectory() as tmp:
        jobs = pathlib.Path(tmp) / "jobs.toml"
        jobs.write_text(
            f'scene = "{scene_path}"\n[random]\ncount = {a.n}\nseed = {a.seed}\n'
        )
        out = pathlib.Path(tmp) / "out"
        subprocess.run(
            [a.terrain, "batch", str(jobs), "--out-dir", str(out), "--size", str(a.size)],
            check=True,
            capture_output=True,
        )
        lines = [json.loads(l) for l in (out / "manifest.jsonl").read_text().splitlines()]
        batch = [l["seconds"] for l in lines if l["status"] == "ok"]

    scene = terrain.Scene.load(scene_path)
    cameras = terrain.random_cameras(scene, a.n, seed=a.seed)
    renderer = terrain.Renderer(scene, size=a.size)
    renderer.render(camera=cameras[0])  # warm-up, as batch's first item compiles its pipelines
    python = []
    for c in cameras:
        t0 = time.perf_counter()
        renderer.render(camera=c)
        python.append(time.perf_counter() - t0)

    b, p = statistics.median(batch), statistics.median(python)
    print(json.dumps({
        "snapshots": a.n,
        "size": a.size,
        "adapter": renderer.adapter,
        "batch_median_s": b,
        "python_median_s": p,
        "python_over_batch": p / b,
    }))


if __name__ == "__main__":
    main()
