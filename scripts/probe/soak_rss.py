#!/usr/bin/env python3
"""Memory soak: renders a long animation through one `gi.Renderer` and records the process's
resident set size (RSS) after every frame.

The scene is `cornell-anim` (its light circles, its tall box slides and turns), stretched so
that every frame is a new pose: the whole 4 s animation spread over all frames. On lavapipe
the "GPU" memory (buffers, textures) is host memory, so RSS covers it too.

    nice -n 10 .venv/bin/python scripts/probe/soak_rss.py --out docs/bench/rss.md

Exits with status 1 when RSS after the warm-up frames leaves the band of +-tolerance around
its value at the end of the warm-up.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import gi


def rss_bytes() -> int:
    """Current resident set size (Linux: /proc/self/statm, resident pages)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="cornell-anim")
    p.add_argument("--method", default="ispm")
    p.add_argument("--frames", type=int, default=1000)
    p.add_argument("--warmup", type=int, default=50, help="frames before the band is checked")
    p.add_argument("--size", default="64x48")
    p.add_argument("--photons", type=int, default=5000)
    p.add_argument("--tolerance", type=float, default=0.05)
    p.add_argument("--out", type=Path, help="write the result table (markdown) here")
    args = p.parse_args(argv)
    if not 0 < args.warmup < args.frames:
        p.error("need 0 < --warmup < --frames")
    w, h = (int(v) for v in args.size.split("x"))

    scene = gi.load_scene(args.scene)
    duration = scene.animation_duration
    if duration is None:
        p.error(f"{args.scene} has no animation")
    start_rss = rss_bytes()
    renderer = gi.Renderer(scene, args.method, size=(w, h), photons=args.photons)
    fps = args.frames / duration  # the whole animation over all frames: every frame moves
    rss = np.zeros(args.frames)
    means = np.zeros(args.frames)
    t0 = time.monotonic()
    for n, frame in renderer.render_animation(range(args.frames), fps=fps):
        means[n] = frame.radiance.mean()
        del frame
        rss[n] = rss_bytes()
        if n % 100 == 0:
            print(f"frame {n:5d}: RSS {rss[n] / 2**20:8.1f} MiB", file=sys.stderr)
    seconds = time.monotonic() - t0

    ref = rss[args.warmup]
    after = rss[args.warmup :]
    signed = (after - ref) / ref
    deviation = np.abs(signed)
    worst = int(np.argmax(deviation)) + args.warmup
    slope = np.polyfit(np.arange(args.warmup, args.frames), after, 1)[0]
    ok = deviation.max() <= args.tolerance
    mib = 2**20

    command = " ".join(["scripts/probe/soak_rss.py", *(argv if argv is not None else sys.argv[1:])])
    lines = [
        "# Memory soak: RSS over a long animation",
        "",
        f"Command: `nice -n 10 .venv/bin/python {command}`",
        "",
        f"{args.frames} frames of `{args.scene}` (moving light and object, a new pose every"
        f" frame) through one `gi.Renderer`, method `{args.method}`, {w}x{h},"
        f" {args.photons} photons; {os.cpu_count()} CPUs ({platform.machine()}),"
        f" {adapter_name()}. {seconds:.0f} s in all"
        f" ({seconds / args.frames * 1000:.0f} ms a frame). RSS read from"
        " `/proc/self/statm` after every frame (lavapipe's GPU memory is host memory, so it"
        " is included).",
        "",
        f"- RSS before the renderer: {start_rss / mib:.1f} MiB; after frame 0:"
        f" {rss[0] / mib:.1f} MiB; after frame {args.warmup} (the reference):"
        f" {ref / mib:.1f} MiB.",
        f"- Frames {args.warmup}..{args.frames - 1}: min {after.min() / mib:.1f} MiB, max"
        f" {after.max() / mib:.1f} MiB; largest deviation from the reference"
        f" **{signed[worst - args.warmup] * 100:+.2f}%** (frame {worst}); band ±"
        f"{args.tolerance * 100:g}%: **{'within' if ok else 'OUTSIDE'}**.",
        f"- Linear trend over those frames: {slope / 1024:+.2f} KiB a frame"
        f" ({slope * (args.frames - args.warmup) / mib:+.2f} MiB over the run).",
        "",
        "| frame | RSS (MiB) | change from frame " + str(args.warmup) + " |",
        "|---:|---:|---:|",
    ]
    marks = sorted(
        n
        for n in {0, 1, 2, 5, 10, 25, args.warmup, args.frames - 1, *range(100, args.frames, 100)}
        if n < args.frames
    )
    for n in marks:
        lines.append(f"| {n} | {rss[n] / mib:.1f} | {(rss[n] - ref) / ref * 100:+.2f}% |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
    return 0 if ok else 1


def adapter_name() -> str:
    report = gi.adapter_report()
    first = report.strip().splitlines()[0] if report.strip() else "adapter: unknown"
    return first.strip()


if __name__ == "__main__":
    sys.exit(main())
