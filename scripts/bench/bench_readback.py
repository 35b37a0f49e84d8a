"""Still frames of a persistent renderer: the time of the native render call (composite,
readback, images to numpy), median over frames, for the readback table of
``docs/bench/frame.md``. Run it once per build to compare (PYTHONPATH to each build's
package, alternating).

    python scripts/bench/bench_readback.py [--method direct] [--size 1920x1080] [--frames 40]
"""

from __future__ import annotations

import argparse
import statistics
import time

import gi


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--method", default="direct")
    p.add_argument("--scene", default="cornell")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--frames", type=int, default=40)
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    r = gi.Renderer(gi.load_scene(a.scene), method=a.method, width=w, height=h)
    out = r.render()  # the first frame renders everything; the rest are still frames
    times = []
    for _ in range(a.frames):
        t = time.perf_counter()
        out = r.render()
        times.append(time.perf_counter() - t)
    stages = ", ".join(f"{n} {s * 1e3:.1f}" for n, s in out.stats.stages)
    print(
        f"{a.method} {a.scene} {w}x{h}: still frame median {statistics.median(times) * 1e3:.1f} ms"
        f" over {a.frames} (last frame's stages, ms: {stages})"
    )


if __name__ == "__main__":
    main()
