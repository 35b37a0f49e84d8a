"""ispm denoising: FLIP against `path` of ispm at its defaults, noisy against the photon-scale
indirect filter (`gi.denoising.filter_indirect`) alone and followed by OIDN (`gi.denoise`'s
pipeline for ispm), for filter widths of 1/32 .. 1/12 of the image width; mean ratio
(filtered / noisy) over seeds 1-3.

Usage: .venv/bin/python scripts/probe/ispm_denoise_sweep.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import gi
from gi.denoising import denoise_image, filter_indirect

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared
from shared import flip  # noqa: E402


def main() -> None:
    scene = gi.load_scene("cornell")
    print("| size | reference spp | " + " | ".join(f"w/{k}" for k in (32, 24, 16, 12)) + " |")
    print("|---|---|" + "---|" * 4)
    for size, spp in (((48, 48), 1024), ((96, 96), 1024), ((192, 192), 512)):
        ref = gi.render(scene, "path", spp=spp, size=size, seed=1000).radiance
        res: dict[str, list[float]] = {}
        for seed in (1, 2, 3):
            r = gi.render(scene, "ispm", size=size, seed=seed, adapter="cpu")
            noisy = flip(ref, r.radiance)
            d = r.aov("direct") + r.aov("specular")
            for k in (32, 24, 16, 12):
                ind = filter_indirect(
                    r.aov("indirect"), r.albedo, r.normal, r.depth, sigma_px=size[0] / k
                )
                filt = d + ind
                res.setdefault(f"{k}", []).append(flip(ref, filt) / noisy)
                both = denoise_image(filt, r.albedo, r.normal)
                res.setdefault(f"{k}+", []).append(flip(ref, both) / noisy)
        cells = [
            f"{np.mean(res[str(k)]):.3f} / {np.mean(res[f'{k}+']):.3f}" for k in (32, 24, 16, 12)
        ]
        print(f"| {size[0]}² | {spp} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
