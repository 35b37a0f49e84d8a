"""Camera-moved `direct` frames with and without the edge mask of the sub-pixel G-buffer
passes (``GI_EDGE_MASK=0`` turns it off; read at every frame), interleaved frame by frame
in one renderer, for ``docs/bench/lights-gpu.md``: the median frame and G-buffer stage of
each.

    python scripts/bench/bench_edge_mask.py [--scene cornell] [--size 640x480] [--frames 15]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import gi


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="cornell")
    p.add_argument("--size", default="640x480")
    p.add_argument("--frames", type=int, default=15)
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    r = gi.Renderer(gi.load_scene(a.scene), method="direct", width=w, height=h)
    r.render()
    x0 = r.describe("camera")["position"]
    frame: dict[str, list[float]] = {"0": [], "1": []}
    gbuffer: dict[str, list[float]] = {"0": [], "1": []}
    for i in range(2 * a.frames):
        mask = "01"[i % 2]
        os.environ["GI_EDGE_MASK"] = mask
        r.update(camera={"position": [x0[0] + 1e-3 * (i + 1), x0[1], x0[2]]})
        t = time.perf_counter()
        out = r.render()
        frame[mask].append(time.perf_counter() - t)
        gbuffer[mask].append(sum(s for n, s in out.stats.stages if n == "gbuffer"))
    for mask, name in (("0", "without mask"), ("1", "with mask")):
        print(
            f"{a.scene} {w}x{h} {name}: frame {statistics.median(frame[mask]) * 1e3:.0f} ms, "
            f"gbuffer {statistics.median(gbuffer[mask]) * 1e3:.0f} ms (median of {a.frames})"
        )


if __name__ == "__main__":
    main()
