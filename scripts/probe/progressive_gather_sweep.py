"""Progressive `gather` settings on cornell: relMSE at power-of-two passes per setting, and
where the error sits (pixels near geometric edges vs the rest).

Uses the 32768-spp reference that `bench_progressive.py --scenes cornell --size 128x128
--ref-spp 32768` caches in target/. Variants are `photons/smoothing/alpha[/nobc]` (nobc:
boundary compensation off):

    .venv/bin/python scripts/probe/progressive_gather_sweep.py 10000/0.3/0.7 30000/0.6/0.9/nobc
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from shared import relmse  # noqa: E402


def edge_mask(scene, size) -> np.ndarray:
    """Pixels within 2 pixels of a change of the first-hit normal."""
    n = gi.render(scene, "path", spp=1, size=size).normal
    edge = np.zeros(n.shape[:2], bool)
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            shifted = np.roll(np.roll(n, dy, 0), dx, 1)
            edge |= np.abs(shifted - n).sum(-1) > 0.5
    return edge


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("variants", nargs="+")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--passes", type=int, default=256)
    args = ap.parse_args()
    size = (args.size, args.size)
    scene = gi.load_scene("cornell")
    ref, _ = reference("cornell", size, 32768, 1234)
    edge = edge_mask(scene, size)
    print(f"edge pixels: {edge.mean():.3f} of the image")
    for v in args.variants:
        photons, smoothing, alpha, *flags = v.split("/")
        r = gi.Renderer(
            scene,
            "gather",
            size=size,
            progressive=True,
            spp=1,
            photons=int(photons),
            smoothing=float(smoothing),
            progressive_alpha=float(alpha),
            boundary_compensation="nobc" not in flags,
        )
        row = []
        for n in range(1, args.passes + 1):
            x = r.render().radiance
            if n & (n - 1) == 0 or n == args.passes:
                row.append(f"{n}:{relmse(x, ref):.2e}")
        e = (x - ref) ** 2 / (ref**2 + 1e-2)
        signed = (x - ref) / (ref + 0.1)
        print(
            v,
            " ".join(row),
            f"| edge share of error {e[edge].sum() / e.sum():.2f},"
            f" mean signed error edge {signed[edge].mean():+.4f}"
            f" rest {signed[~edge].mean():+.4f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
