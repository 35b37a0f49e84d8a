"""`photon` against `path`: image means, for the direct light of the suns and point lights
by next-event estimation (issue 47). Run with the extension to measure (before/after by
swapping python/gi/_gi.abi3.so):

    /work/wt/dev.sh python scripts/probe/photon_nee_lights.py
"""

import sys
import warnings
from pathlib import Path

import gi

ROOT = Path(__file__).resolve().parents[2]
CASES = [
    (
        "khronos_normal_tangent_mirror",
        ROOT / "tests/scenes/gltf/khronos_normal_tangent_mirror.json",
        {"spp": 16, "photons": 50_000},
    ),
    ("cornell", "cornell", {"spp": 16, "photons": 50_000}),
]


def load(src):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.AssetWarning)
        return gi.load_scene(src)


def main():
    for name, src, kw in CASES:
        scene = load(src)
        ref = gi.render(scene, "path", spp=64, seed=1).radiance.mean()
        got = gi.render(scene, "photon", seed=1, **kw).radiance.mean()
        print(f"{name}: path {ref:.5f} photon {got:.5f} ({got / ref - 1:+.2%}) {kw}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
