"""The glossy (GGX) reflection of the sky in every method against `path`: the mean of the
object's pixels, relative to `path`'s, on a convex glossy sphere under a constant sky
(where the answer is L·albedo(μ)) and on Khronos' DamagedHelmet and NormalTangentMirrorTest
(tests/scenes/gltf/, the corpus test's settings). Prints a Markdown table.

    .venv/bin/python scripts/bench/bench_glossy_sky.py > table.md

Run against another build (PYTHONPATH pointing at a package with its extension) for the
"before" column of docs/bench/glossy-sky.md.
"""

from __future__ import annotations

import json
import tempfile
import warnings
from pathlib import Path

import numpy as np

import gi

ROOT = Path(__file__).resolve().parents[2]
CORPUS = ROOT / "tests" / "scenes" / "gltf"
MODELS = ["khronos_damaged_helmet", "khronos_normal_tangent_mirror"]
# The corpus test's settings (tests/test_gltf_corpus.py OTHERS).
CORPUS_SETTINGS = {
    "direct": {"spp": 4},
    "ispm": {"spp": 4, "photons": 50_000},
    "bidir": {"spp": 4},
    "photon": {"spp": 16, "photons": 50_000},
    "gather": {"spp": 16, "photons": 50_000},
}
# tests/test_glossy_sky.py's settings.
SPHERE_SETTINGS = {
    **CORPUS_SETTINGS,
    "ispm": {"spp": 4, "photons": 20_000},
    "photon": {"spp": 16, "photons": 200_000},
    "gather": {"spp": 16, "photons": 200_000},
}


def glossy_sphere(folder: Path, roughness: float):
    desc = {
        "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 40},
        "materials": {
            "metal": {"diffuse": [0, 0, 0], "specular": [0.9] * 3, "roughness": roughness}
        },
        "objects": [
            {"shape": {"type": "sphere", "radius": 1.0}, "material": "metal", "smooth": False}
        ],
        "environment": {"radiance": [1, 1, 1]},
    }
    desc["camera"].update(width=24, height=24)
    path = folder / f"sphere_{roughness}.json"
    path.write_text(json.dumps(desc))
    return gi.load_scene(path)


def interior(mask):
    m = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            m &= np.roll(np.roll(mask, dy, 0), dx, 1)
    m[[0, -1], :] = False
    m[:, [0, -1]] = False
    return m


def row(label, scene, settings, seed, shrink):
    ref = gi.render(scene, "path", spp=64, seed=1)
    obj = ref.depth > 0
    obj = interior(obj) if shrink else obj
    expected = ref.radiance[obj].mean()
    cells = []
    for method, kw in settings.items():
        r = gi.render(scene, method, seed=seed, **kw) if seed else gi.render(scene, method, **kw)
        cells.append(f"{100 * (r.radiance[obj].mean() / expected - 1):+.1f}%")
    return f"| {label} | {expected:.4f} | " + " | ".join(cells) + " |"


def main():
    warnings.simplefilter("ignore")
    methods = list(CORPUS_SETTINGS)
    print("| scene | path (mean) | " + " | ".join(methods) + " |")
    print("|---|---|" + "---|" * len(methods))
    with tempfile.TemporaryDirectory() as tmp:
        for rough in (0.001, 0.1, 0.3):
            scene = glossy_sphere(Path(tmp), rough)
            print(row(f"sphere, roughness {rough}", scene, SPHERE_SETTINGS, 2, True))
    for name in MODELS:
        scene = gi.load_scene(CORPUS / f"{name}.json")
        print(row(name, scene, CORPUS_SETTINGS, None, False))


if __name__ == "__main__":
    main()
