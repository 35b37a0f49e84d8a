"""Still frames of a persistent renderer: the time of the render call (composite,
readback, images to numpy), median over frames, for the readback tables of
``docs/bench/frame.md``. Run it once per build to compare (PYTHONPATH to each build's
package, alternating).

    python scripts/bench/bench_readback.py [--method direct] [--size 1920x1080] [--frames 40]
        [--readouts]

``--readouts`` (issue 45): in one run, frames interleaved, the viewer's frame as it was
(the float radiance read back, tone-mapped and quantized by numpy, ``gi.display.to_srgb8``)
against the radiance read back as half floats and the 8-bit display image tone-mapped on
the GPU alone (``radiance=None, tonemap="clip"``): the call's time, its ``readback`` stage
and the bytes read back per pixel.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import gi
from gi.display import to_srgb8

#: (label, bytes per pixel read back, render keywords, what the caller does after).
READOUTS: list[tuple[str, int, dict[str, Any], Callable[[Any], Any]]] = [
    ("float32 + numpy tone map (viewer before)", 16, {}, lambda f: to_srgb8(f.radiance)),
    ("float16", 8, {"radiance": "float16"}, lambda f: f.radiance),
    (
        "8-bit display on the GPU only",
        4,
        {"radiance": None, "tonemap": "clip"},
        lambda f: f.display8,
    ),
]


def _stage(result: gi.RenderResult, name: str) -> float:
    return sum(s for n, s in result.stats.stages if n == name)


def readouts(renderer: gi.Renderer, frames: int, label: str) -> None:
    renderer.render()
    samples: list[tuple[list[float], list[float]]] = [([], []) for _ in READOUTS]
    for _ in range(frames):
        for (_, _, kwargs, after), (wall, readback) in zip(READOUTS, samples, strict=True):
            t = time.perf_counter()
            out = renderer.render(**kwargs)
            after(out)
            wall.append(time.perf_counter() - t)
            readback.append(_stage(out, "readback"))
    print(f"{label}, still frames, median of {frames}:\n")
    print("| readout | bytes/pixel | frame incl. the 8-bit image (ms) | readback stage (ms) |")
    print("|---|---|---|---|")
    for (name, size, _, _), (wall, readback) in zip(READOUTS, samples, strict=True):
        med = statistics.median
        print(f"| {name} | {size} | {med(wall) * 1e3:.1f} | {med(readback) * 1e3:.2f} |")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--method", default="direct")
    p.add_argument("--scene", default="cornell")
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--frames", type=int, default=40)
    p.add_argument("--readouts", action="store_true")
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    r = gi.Renderer(gi.load_scene(a.scene), method=a.method, width=w, height=h)
    if a.readouts:
        readouts(r, a.frames, f"{a.method} {a.scene} {w}x{h}")
        return
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
