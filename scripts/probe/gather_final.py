#!/usr/bin/env python3
"""Method `gather` against `path` with and without its final gather, for footprint
smoothing values (each footprint holds about 240·s² photons): how blotchy its default image
is (issue 46, item 8; docs/bench/gather-smoothing.md). Prints, per configuration:

- relMSE (3×3): mean (x − ref)² / (ref² + 0.01) of both images box-filtered 3×3 (the
  blotches, a few pixels wide at 128², stay; most pixel noise goes);
- blotch: the same on 8×8 block means (the low-frequency error: what a footprint-sized
  blotch leaves after 64 pixels' averaging, where pixel noise is 64× smaller);
- the ratio of image means, and the time.

    .venv/bin/python scripts/probe/gather_final.py --scene cornell
    .venv/bin/python scripts/probe/gather_final.py --scene cornell-glass --ref /tmp/cg.exr
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import gi


def box3(img: np.ndarray) -> np.ndarray:
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = img.shape[:2]
    return sum(p[y : y + h, x : x + w] for y in range(3) for x in range(3)) / 9.0


def blocks(img: np.ndarray, b: int = 8) -> np.ndarray:
    h, w = img.shape[0] // b * b, img.shape[1] // b * b
    return img[:h, :w].reshape(h // b, b, w // b, b, -1).mean(axis=(1, 3))


def rel_mse(a: np.ndarray, ref: np.ndarray) -> float:
    return float(np.mean((a - ref) ** 2 / (ref**2 + 0.01)))


def reference(args, size) -> np.ndarray:
    if args.ref and Path(args.ref).is_file():
        return gi.read_image(args.ref)[..., :3]
    img = gi.render(args.scene, "path", spp=args.ref_spp, size=size, seed=7).radiance
    if args.ref:
        gi.save_image(args.ref, img)
    return img


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--ref", help="the path reference (EXR; rendered and written if absent)")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--spp", default="8", help="camera samples, comma-separated")
    ap.add_argument("--photons", type=int, default=200_000)
    ap.add_argument(
        "--configs",
        default="off:1,on:1,on:0.71,on:0.5",
        help="final gather on/off and smoothing, comma-separated",
    )
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    ref = reference(args, size)
    print(
        f"{args.scene} {args.size}, path {args.ref_spp} spp reference; gather {args.photons}"
        f" photons, seed {args.seed}"
    )
    print("| final gather | smoothing | spp | relMSE (3×3) | blotch (8×8) | mean / path's | s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for spp in (int(v) for v in args.spp.split(",")):
        for config in args.configs.split(","):
            fg, s = config.split(":")
            t = time.monotonic()
            img = gi.render(
                args.scene,
                "gather",
                spp=spp,
                size=size,
                photons=args.photons,
                smoothing=float(s),
                final_gather=fg == "on",
                seed=args.seed,
            ).radiance
            dt = time.monotonic() - t
            err = rel_mse(box3(img), box3(ref))
            blotch = rel_mse(blocks(img), blocks(ref))
            print(
                f"| {fg} | {s} | {spp} | {err:.4g} | {blotch:.3g} |"
                f" {img.mean() / ref.mean():.3f} | {dt:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
