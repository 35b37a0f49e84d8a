"""Shadow-map size against the direct light's error and its cost per frame.

For each scene, method ``direct`` (16 sub-pixel samples, edge-adaptive supersampling) at
each shadow-map size: the FLIP and relMSE of its image against a ``path`` reference of the
direct light alone (``max_depth`` 1), and the median wall time of frames whose light moves a
little before each (so that every frame re-renders the shadow maps and re-lights the
image), as a markdown table. The reference's own noise is that of a second reference of
another seed.

    .venv/bin/python scripts/bench/bench_shadow_size.py [--scenes cornell mirror-shadow]
        [--size 640x480] [--sizes 256 512 1024 2048] [--ref-spp 512] [--frames 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from shared import flip, relmse  # noqa: E402


def moving_light_ms(scene: gi.Scene, size: tuple[int, int], shadow: int, frames: int) -> float:
    """Median wall milliseconds of `frames` frames of method ``direct``, light 0 moved 1 cm
    along x before each (after a warm-up frame)."""
    r = gi.Renderer(scene, "direct", size=size, spp=16, shadow_map_size=shadow)
    r.render()
    position = r.describe("light", 0)["position"]
    times = []
    for i in range(frames):
        r.update(lights={0: {"position": [position[0] + 0.01 * (i + 1), *position[1:]]}})
        t = time.perf_counter()
        r.render()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=["cornell", "mirror-shadow"])
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--sizes", nargs="+", type=int, default=[256, 512, 1024, 2048])
    ap.add_argument("--ref-spp", type=int, default=512)
    ap.add_argument("--frames", type=int, default=5)
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    size = (w, h)
    print(f"`scripts/bench/bench_shadow_size.py --size {a.size} --ref-spp {a.ref_spp}`\n")
    print("| scene | shadow map | FLIP | relMSE | frame, light moving (ms) |")
    print("|---|---|---|---|---|")
    for name in a.scenes:
        scene = gi.load_scene(name)
        r1, r2 = (
            gi.render(scene, "path", spp=a.ref_spp, size=size, max_depth=1, seed=seed).radiance
            for seed in (1234, 4321)
        )
        print(f"| {name} | reference's own noise | {flip(r1, r2):.4f} | {relmse(r2, r1):.2e} | |")
        for s in a.sizes:
            img = gi.render(scene, "direct", spp=16, size=size, shadow_map_size=s).radiance
            ms = moving_light_ms(scene, size, s, a.frames)
            print(f"| {name} | {s}² | {flip(r1, img):.4f} | {relmse(img, r1):.2e} | {ms:.0f} |")


if __name__ == "__main__":
    main()
