"""GPU probe (scripts/gpu_check.sh part p), second round on the sky's shadow-mapped
directions: the first (sky_shadows.py, H100 2026-11-26) found one direction exact on the
GPU (equal to lavapipe) but 16 wrong (a floor alone falsely shadowed in straight-edged
regions: layers other than the first looked up against another view). This bisects: a floor
alone with 2, 4 and 8 directions; a floor and a sphere under two suns (two orthographic
layers of the scene's shadow maps), under an area light (16 points, 96 cube layers of the
sampled-light maps), and under the sky with an emitter as well (the sky's layers after the
emitters'). Writes probe.json (floor and image means per case) and probe.npz.

    GI_ADAPTER=cpu python scripts/gpu_probes/sky_shadows_2.py /tmp/probe2-lavapipe
"""

from __future__ import annotations

import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import gi

FLOOR = {
    "shape": {"type": "quad", "size": [6, 6]},
    "transform": {"translate": [0, -0.5, 0]},
    "material": "m",
}
SPHERE = {"shape": {"type": "sphere", "radius": 0.5, "subdivisions": 4}, "material": "m"}
LAMP = {
    "shape": {"type": "quad", "size": [0.6, 0.6]},
    "transform": {"rotate": [180, 0, 0], "translate": [0.4, 1.6, 0.2]},
    "material": "lamp",
}
SUNS = [
    {"type": "directional", "direction": [0.4, -1, 0.3], "irradiance": [2, 2, 2]},
    {"type": "directional", "direction": [-0.6, -1, -0.2], "irradiance": [1, 1, 1]},
]
SKY = {"radiance": [1.0, 1.0, 1.0]}


def scene(folder: Path, name: str, objects: list, lights=(), environment=None) -> gi.Scene:
    desc: dict = {
        "camera": {
            "position": [0, 0.8, 3],
            "look_at": [0, -0.1, 0],
            "fov": 40,
            "width": 48,
            "height": 48,
        },
        "materials": {
            "m": {"diffuse": [0.5, 0.5, 0.5]},
            "lamp": {"diffuse": [0, 0, 0], "emission": [8, 8, 8]},
        },
        "objects": objects,
        "lights": list(lights),
    }
    if environment:
        desc["environment"] = environment
    path = folder / f"{name}.json"
    path.write_text(json.dumps(desc))
    return gi.load_scene(path)


def main() -> int:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp())
    floor = scene(folder, "floor", [FLOOR], environment=SKY)
    cases = []
    for n in (2, 4, 8):
        for seed in range(4):
            cases.append((f"floor_sky_n{n}_seed{seed}", floor, dict(sky_samples=n, seed=seed)))
    suns = scene(folder, "suns", [FLOOR, SPHERE], lights=SUNS)
    cases.append(("suns2", suns, {}))
    one_sun = scene(folder, "sun", [FLOOR, SPHERE], lights=SUNS[1:])
    cases.append(("sun1", one_sun, {}))
    lamp = scene(folder, "lamp", [FLOOR, SPHERE, LAMP])
    for n in (1, 2, 16):
        cases.append((f"lamp_area{n}", lamp, dict(area_samples=n)))
    both = scene(folder, "both", [FLOOR, SPHERE, LAMP], environment=SKY)
    for n in (1, 16):
        cases.append((f"lamp_sky_n{n}", both, dict(area_samples=4, sky_samples=n)))
    images, rows = {}, []
    for key, sc, kw in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = gi.render(sc, "direct", shadow_map_size=1024, **kw)
        img = np.asarray(r.radiance, np.float32)
        images[key] = img
        on_floor = (r.depth > 0) & (np.abs(np.asarray(r.position)[..., 1] + 0.5) < 1e-3)
        mean = float(img[on_floor].mean()) if on_floor.any() else float("nan")
        rows.append({"case": key, "floor_mean": mean, "image_mean": float(img.mean())})
        print(f"{key}: floor {mean:.4f}, image {img.mean():.4f}", flush=True)
    np.savez_compressed(out / "probe.npz", **images)
    report = {"adapter": gi.adapter_report(), "rows": rows}
    (out / "probe.json").write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
