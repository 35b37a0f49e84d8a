"""GPU probe (scripts/ci/gpu_check.sh part p): the sky's shadow-mapped directions on a floor.

On the H100 (2026-11-26) the sky's direct light in `direct` and `ispm` was 18-29% off where
a floor is lit (tests/test_environment.py, crates/core/tests/gpu_lights.rs), while a convex
object alone under the sky was exact and lavapipe passes (fixed since: docs/gpu-check.md,
"Runs"). Method `direct` on a floor (alone, where nothing can shadow it: exactly albedo x
sky, 0.5, whatever the directions; or with a sphere) under a constant sky:

- first round: one direction per seed and 16, at three sample-map sizes, two floor sizes;
- second round (bisecting): a floor alone with 2, 4 and 8 directions; a floor and a sphere
  under two suns (two orthographic layers of the scene's shadow maps), under an area light
  (1, 2, 16 points: cube layers of the sampled-light maps), and under the sky with an
  emitter as well (the sky's layers after the emitters').

Writes every image (probe.npz) and the floor's and image's mean per case (probe.json), to be
compared with the same script's output on lavapipe:

    GI_ADAPTER=cpu python scripts/probe/gpu_probes/sky_shadows.py /tmp/probe-lavapipe
"""

from __future__ import annotations

import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import gi

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


def floor(size: float) -> dict:
    return {
        "shape": {"type": "quad", "size": [size, size]},
        "transform": {"translate": [0, -0.5, 0]},
        "material": "m",
    }


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


def cases(folder: Path) -> list[tuple[str, gi.Scene, dict]]:
    out = []
    # First round.
    for sphere in (False, True):
        for size in (2.0, 6.0):
            objects = [floor(size), SPHERE] if sphere else [floor(size)]
            sc = scene(folder, f"floor-{int(sphere)}-{size:g}", objects, environment=SKY)
            for n in (1, 16):
                for map_size in (256, 1024, 4096):
                    for seed in range(6) if n == 1 else (7,):
                        key = f"sphere{int(sphere)}_floor{size:g}_n{n}_map{map_size}_seed{seed}"
                        out.append(
                            (key, sc, dict(sky_samples=n, shadow_map_size=map_size, seed=seed))
                        )
    # Second round.
    alone = scene(folder, "floor", [floor(6.0)], environment=SKY)
    for n in (2, 4, 8):
        for seed in range(4):
            out.append((f"floor_sky_n{n}_seed{seed}", alone, dict(sky_samples=n, seed=seed)))
    out.append(("suns2", scene(folder, "suns", [floor(6.0), SPHERE], lights=SUNS), {}))
    out.append(("sun1", scene(folder, "sun", [floor(6.0), SPHERE], lights=SUNS[1:]), {}))
    lamp = scene(folder, "lamp", [floor(6.0), SPHERE, LAMP])
    for n in (1, 2, 16):
        out.append((f"lamp_area{n}", lamp, dict(area_samples=n)))
    both = scene(folder, "both", [floor(6.0), SPHERE, LAMP], environment=SKY)
    for n in (1, 16):
        out.append((f"lamp_sky_n{n}", both, dict(area_samples=4, sky_samples=n)))
    return out


def main() -> int:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    images, rows = {}, []
    for key, sc, options in cases(Path(tempfile.mkdtemp())):
        options = {"shadow_map_size": 1024, **options}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = gi.render(sc, "direct", **options)
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
