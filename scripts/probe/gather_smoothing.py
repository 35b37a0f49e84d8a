#!/usr/bin/env python3
"""Method `gather` against `path`, for footprint smoothing values (each footprint holds
about 240·s² photons): the blotches of its default image (issue 46, item 8). Prints relMSE =
mean (x − ref)² / (ref² + 0.01) on a 3×3 box-filtered image (what blotches add, the pixel
noise of low spp mostly not), the ratio of image means, and the time
(docs/bench/gather-smoothing.md).

    .venv/bin/python scripts/probe/gather_smoothing.py --scene cornell --photons 200000
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import gi


def box3(img: np.ndarray) -> np.ndarray:
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = img.shape[:2]
    return sum(p[y : y + h, x : x + w] for y in range(3) for x in range(3)) / 9.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--photons", type=int, default=200_000)
    ap.add_argument("--smoothing", default="0.71,1,1.41")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    ref = box3(gi.render(args.scene, "path", spp=args.ref_spp, size=size, seed=7).radiance)
    print(
        f"{args.scene} {args.size}, path {args.ref_spp} spp reference; gather {args.spp} spp,"
        f" {args.photons} photons"
    )
    print("| smoothing | relMSE (3×3 box) | mean / path's | seconds |")
    print("|---:|---:|---:|---:|")
    for s in (float(v) for v in args.smoothing.split(",")):
        t = time.monotonic()
        img = gi.render(
            args.scene,
            "gather",
            spp=args.spp,
            size=size,
            photons=args.photons,
            smoothing=s,
            seed=3,
        ).radiance
        dt = time.monotonic() - t
        err = np.mean((box3(img) - ref) ** 2 / (ref**2 + 0.01))
        print(f"| {s:g} | {err:.4g} | {img.mean() / ref.mean():.3f} | {dt:.1f} |", flush=True)


if __name__ == "__main__":
    main()
