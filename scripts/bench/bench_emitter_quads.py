"""Camera-moved `direct` frames with the closed-form emitter polygons merged into quads and
without (``GI_EMITTER_QUADS=0``: every triangle its own polygon; read when a renderer first
draws its emitters), two renderers interleaved frame by frame, for
``docs/bench/lights-gpu.md``: the median frame and `direct light` stage of each, and the
largest pixel difference of their images.

    python scripts/bench/bench_emitter_quads.py [--scenes emissive-room cornell-box]
        [--size 640x480] [--frames 9]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

import gi

ROOT = Path(__file__).resolve().parents[2]


def renderer(name: str, quads: str, w: int, h: int) -> gi.Renderer:
    os.environ["GI_EMITTER_QUADS"] = quads
    scene = gi.load_scene(ROOT / "docs" / "scenes" / name / f"{name}.xml")
    r = gi.Renderer(scene, method="direct", width=w, height=h, seed=1)
    r.render()
    os.environ.pop("GI_EMITTER_QUADS")
    return r


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenes", nargs="+", default=["emissive-room", "cornell-box"])
    p.add_argument("--size", default="640x480")
    p.add_argument("--frames", type=int, default=9)
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    print("| scene | polygons | frame (ms) | direct light (ms) |")
    print("|---|---|---|---|")
    for name in a.scenes:
        rs = {q: renderer(name, q, w, h) for q in ("0", "1")}
        x0 = rs["0"].describe("camera")["position"]
        frame: dict[str, list[float]] = {"0": [], "1": []}
        light: dict[str, list[float]] = {"0": [], "1": []}
        images = {}
        for i in range(2 * a.frames):
            q = "01"[i % 2]
            r = rs[q]
            r.update(camera={"position": [x0[0] + 1e-3 * (i // 2 % 2), x0[1], x0[2]]})
            t = time.perf_counter()
            out = r.render()
            frame[q].append(time.perf_counter() - t)
            light[q].append(sum(s for n, s in out.stats.stages if n == "direct light"))
            images[q] = np.asarray(out.radiance)
        diff = float(np.abs(images["0"] - images["1"]).max())
        peak = float(images["0"].max())
        for q, label in (("0", "triangles"), ("1", "quads")):
            print(
                f"| {name} | {label} | {statistics.median(frame[q]) * 1e3:.0f} | "
                f"{statistics.median(light[q]) * 1e3:.0f} |"
            )
        print(f"\n{name}: largest pixel difference {diff:.2e} (brightest pixel {peak:.3g})\n")


if __name__ == "__main__":
    main()
