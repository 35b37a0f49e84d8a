"""`bidir` against `path` on the glTF corpus's Khronos models under their sky (issue 47): the
image mean's ratio per seed and over seeds 1–4 (the test's settings: `bidir` 4 spp, `path`
64 spp seed 1). Prints a Markdown table (`docs/bench/bidir-depth.md`, issue 47 section).

    python scripts/probe/bidir_glossy_sky.py [--label NAME]
"""

import argparse
import warnings
from pathlib import Path

import numpy as np

import gi

CORPUS = Path(__file__).resolve().parents[2] / "tests" / "scenes" / "gltf"
NAMES = sorted(p.stem for p in CORPUS.glob("khronos_*.json"))


def load(name: str) -> gi.Scene:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.AssetWarning)
        return gi.load_scene(CORPUS / f"{name}.json")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--label", default="")
    label = ap.parse_args().label
    print(f"| {label} model | bidir/path seeds 1–4 | mean |")
    print("|---|---|---|")
    for name in NAMES:
        scene = load(name)
        ref = float(gi.render(scene, "path", spp=64, seed=1).radiance.mean())
        frames = [gi.render(scene, "bidir", spp=4, seed=s).radiance for s in range(1, 5)]
        ratios = [float(f.mean()) / ref for f in frames]
        cells = " ".join(f"{r:.3f}" for r in ratios)
        print(f"| {name} | {cells} | {np.mean(ratios):.3f} |")


if __name__ == "__main__":
    main()
