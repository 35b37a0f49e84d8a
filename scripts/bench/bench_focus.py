"""Photon focusing share (`photon_focus`, method gather) against FLIP and relMSE.

Gather at 200k photons, 4 spp, 48x48, means over seeds 0 and 1, scored against the cached
`path` references of scripts/bench/bench_progressive.py (16384 spp). Prints a Markdown table.

    .venv/bin/python scripts/bench/bench_focus.py >> docs/bench/caustics.md
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from shared import flip, relmse  # noqa: E402


def main() -> None:
    print("\n## Photon focusing share (gather)\n")
    print("Made by `.venv/bin/python scripts/bench/bench_focus.py >> docs/bench/caustics.md`.\n")
    print("| scene | photon_focus | FLIP | relMSE |")
    print("|---|---:|---:|---:|")
    for name in ["cornell-glass", "caustic-ring", "mirror-shadow"]:
        ref, _ = reference(name, (48, 48), 16384, 1234)
        scene = gi.load_scene(name)
        for f in [0.0, 0.1, 0.25, 0.5]:
            scores = []
            for seed in (0, 1):
                img = gi.render(
                    scene,
                    "gather",
                    size=(48, 48),
                    photons=200_000,
                    spp=4,
                    seed=seed,
                    photon_focus=f,
                ).radiance
                scores.append((flip(ref, img), relmse(img, ref)))
            fl, rm = np.mean(scores, axis=0)
            print(f"| {name} | {f:g} | {fl:.4f} | {rm:.2e} |", flush=True)


if __name__ == "__main__":
    main()
