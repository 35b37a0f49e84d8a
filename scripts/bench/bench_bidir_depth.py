"""`bidir` at any depth (issue 29): its frame time and error at depths 3, 7 and 64.

Per scene, in one run on the same cores: `bidir` at `max_depth` 3 (two bounces), 7 and its
default (64), `ispm` and `path` at their defaults, each scored against a converged `path`
reference (default depth 64; cached as bench_progressive's): the image mean relative to the
reference's, HDR-FLIP and relMSE, and the frame's wall-clock seconds (the mean of --frames
frames of a warm renderer, seeds 1, 2, …; the error columns are those of the first frame).

    GI_REF_CACHE=/work/cache/refs .venv/bin/python scripts/bench/bench_bidir_depth.py \\
        --out docs/bench/bidir-depth.md

`--tag before --bidir-only` (run with an older build's interpreter) gives rows to set beside
a newer build's: `docs/bench/bidir-depth.md` has main's and issue 29's MIS change so.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from shared import cpu_name, flip, relmse  # noqa: E402

RUNS = [
    ("bidir", "`bidir` max_depth 3", dict(max_depth=3)),
    ("bidir", "`bidir` max_depth 7", dict(max_depth=7)),
    ("bidir", "`bidir` defaults (max_depth 64)", {}),
    ("ispm", "`ispm` defaults", dict(adapter="cpu")),
    ("path", "`path` defaults", {}),
]


def timed(scene: gi.Scene, method: str, size, frames: int, settings: dict):
    """(first frame's radiance, mean seconds per frame, stats of the last) of a warm
    renderer."""
    r = gi.Renderer(scene, method, size=size, seed=1, **settings)
    first = r.render().radiance
    seconds = 0.0
    stats = None
    for seed in range(2, frames + 2):
        t = time.perf_counter()
        out = r.render(seed=seed)
        seconds += time.perf_counter() - t
        stats = out.stats
    return first, seconds / frames, stats


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenes", default="cornell,furnace")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--frames", type=int, default=2)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--tag", default="", help="appended to the `bidir` rows' labels")
    ap.add_argument("--bidir-only", action="store_true", help="no `ispm` and `path` rows")
    a = ap.parse_args()
    size = (a.size, a.size)
    lines = [
        "# `bidir` at any depth (issue 29)",
        "",
        "Command: `GI_REF_CACHE=/work/cache/refs .venv/bin/python"
        " scripts/bench/bench_bidir_depth.py"
        f" --scenes {a.scenes} --size {a.size} --ref-spp {a.ref_spp} --frames {a.frames}`"
        f" · {a.size}×{a.size} · reference: `path` at {a.ref_spp} spp (max_depth 64) ·"
        f" wall-clock seconds per frame of a warm renderer (mean of {a.frames}) on"
        f" {cpu_name()}, 2 cores shared with other work, lavapipe for the GPU passes ·"
        " mean: the image mean over the reference's (mean of RGB) · FLIP and relMSE of the"
        " first frame.",
        "",
    ]
    for name in a.scenes.split(","):
        scene = gi.load_scene(name)
        ref, ref_s = reference(name, size, a.ref_spp, 7)
        lines += [
            f"## {name}",
            "",
            f"Reference: {ref_s:.0f} s.",
            "",
            "| method | frame (s) | mean / reference | FLIP | relMSE | light subpaths |",
            "|---|---|---|---|---|---|",
        ]
        for method, label, settings in RUNS:
            if a.bidir_only and method != "bidir":
                continue
            if method == "bidir" and a.tag:
                label = f"{label} ({a.tag})"
            img, seconds, stats = timed(scene, method, size, a.frames, settings)
            ratio = float(img.mean() / ref.mean())
            subpaths = stats.light_paths if method == "bidir" else "–"
            row = (
                f"| {label} | {seconds:.3f} | {ratio:.4f} | {flip(ref, img):.4f} |"
                f" {relmse(img, ref):.4f} | {subpaths} |"
            )
            print(name, row, flush=True)
            lines.append(row)
        lines.append("")
    text = "\n".join(lines)
    if a.out:
        a.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
