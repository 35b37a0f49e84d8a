"""The one-frame GPU direct light of emitting objects: error and cost per frame.

For the reference scenes of issue 28 that are lit by emitting surfaces (``docs/scenes/``:
``emissive-room``, ``cornell-box``), methods ``direct`` (against a ``path`` reference of
the direct light alone, ``max_depth`` 1) and ``ispm`` (against ``path`` at ``max_depth``
64), one frame each at the defaults (16 sub-pixel samples, 16 points on the emitters): the
image mean over the reference's, FLIP and relMSE, mean over the frames of three seeds
(each draws its own points); then the median wall time of ``direct`` frames at 640×480
after the camera moved (G-buffer, edges and the direct light redone; the points and their
shadow maps kept). Markdown table on stdout. The references are cached in
``target/emitter-groups-*.npy``.

    .venv/bin/python scripts/bench/bench_emitter_groups.py [--size 128] [--ref-spp 2048]
        [--frames 7] [--area-samples 16] [--scenes emissive-room cornell-box] [--label NAME]

To compare two builds, run it with each on ``PYTHONPATH`` (e.g. the parent commit's wheel
unpacked into a folder) in the same session, alternating.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from shared import flip, relmse  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES = ["emissive-room", "cornell-box"]
METHODS = {"direct": 1, "ispm": 64}  # method: the max_depth of its reference


def load(name: str) -> gi.Scene:
    return gi.load_scene(ROOT / "docs" / "scenes" / name / f"{name}.xml")


def reference(name: str, depth: int, size: int, spp: int) -> np.ndarray:
    cache = ROOT / "target" / f"emitter-groups-{name}-{depth}-{size}-{spp}.npy"
    if cache.exists():
        return np.load(cache)
    r = gi.Renderer(load(name), "path", size=(size, size), spp=spp, max_depth=depth, seed=3)
    img = r.render().radiance[..., :3]
    cache.parent.mkdir(exist_ok=True)
    np.save(cache, img)
    return img


def camera_moved_ms(scene: gi.Scene, frames: int, points: int) -> float:
    """Median wall milliseconds of `frames` ``direct`` frames at 640×480, the camera moved
    1 mm along x and back between them (after a warm-up frame)."""
    r = gi.Renderer(scene, "direct", size=(640, 480), seed=1, area_samples=points)
    r.render()
    position = np.array(r.describe("camera")["position"], float)
    times = []
    for i in range(frames):
        r.update(camera={"position": (position + [0.001 * (i % 2), 0, 0]).tolist()})
        t = time.perf_counter()
        r.render()
        times.append(time.perf_counter() - t)
    return 1000 * statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--frames", type=int, default=7)
    ap.add_argument("--area-samples", type=int, default=16, help="points on the emitters")
    ap.add_argument("--scenes", nargs="+", default=SCENES, choices=SCENES)
    ap.add_argument("--label", default="this build")
    a = ap.parse_args()
    print(f"gi {gi.__version__} ({gi.__file__}), {a.label}, area_samples {a.area_samples}")
    print()
    print("| scene | method | image mean / reference | FLIP | relMSE | camera-moved frame (ms) |")
    print("|---|---|---|---|---|---|")
    for name in a.scenes:
        scene = load(name)
        for method, depth in METHODS.items():
            ref = reference(name, depth, a.size, a.ref_spp)
            rows = []
            for seed in (11, 12, 13):
                size = (a.size, a.size)
                o = {"seed": seed, "spp": 16, "area_samples": a.area_samples}
                r = gi.Renderer(scene, method, size=size, **o)
                img = r.render().radiance[..., :3]
                rows.append((img.mean() / ref.mean(), flip(ref, img), relmse(img, ref)))
            m = np.mean(rows, axis=0)
            direct = method == "direct"
            ms = f"{camera_moved_ms(scene, a.frames, a.area_samples):.0f}" if direct else ""
            row = f"| {name} | {method} | {m[0]:.4f} | {m[1]:.3f} | {m[2]:.5f} | {ms} |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
