"""GPU probe (scripts/gpu_check.sh part p): the sky's shadow-mapped directions on a floor.

On the H100 (2026-11-26) the sky's direct light in `direct` and `ispm` was 18-29% off where
a floor is lit (tests/test_environment.py, crates/core/tests/gpu_lights.rs), while a convex
object alone under the sky was exact and lavapipe passes. This renders a floor alone (every
direction unoccluded: the floor must be exactly albedo x sky, 0.5, whatever the directions)
and a floor with a sphere, with one direction per seed and with 16, at three sample-map
sizes, and writes every image (probe.npz) and the floor's mean per case (probe.json), to be
compared with the same script's output on lavapipe:

    GI_ADAPTER=cpu python scripts/gpu_probes/sky_shadows.py /tmp/probe-lavapipe
"""

from __future__ import annotations

import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import gi


def scene(folder: Path, sphere: bool, floor_size: float) -> gi.Scene:
    objects: list[dict] = [
        {
            "shape": {"type": "quad", "size": [floor_size, floor_size]},
            "transform": {"translate": [0, -0.5, 0]},
            "material": "m",
        }
    ]
    if sphere:
        objects.append(
            {"shape": {"type": "sphere", "radius": 0.5, "subdivisions": 4}, "material": "m"}
        )
    desc = {
        "camera": {
            "position": [0, 0.8, 3],
            "look_at": [0, -0.1, 0],
            "fov": 40,
            "width": 48,
            "height": 48,
        },
        "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
        "objects": objects,
        "environment": {"radiance": [1.0, 1.0, 1.0]},
    }
    path = folder / f"floor-{int(sphere)}-{floor_size:g}.json"
    path.write_text(json.dumps(desc))
    return gi.load_scene(path)


def main() -> int:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp())
    cases = []
    for sphere in (False, True):
        for floor_size in (2.0, 6.0):
            for n in (1, 16):
                for size in (256, 1024, 4096):
                    for seed in range(6) if n == 1 else (7,):
                        cases.append((sphere, floor_size, n, size, seed))
    scenes = {(s, f): scene(folder, s, f) for s in (False, True) for f in (2.0, 6.0)}
    images, rows = {}, []
    for sphere, floor_size, n, size, seed in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = gi.render(
                scenes[sphere, floor_size],
                "direct",
                sky_samples=n,
                shadow_map_size=size,
                seed=seed,
            )
        key = f"sphere{int(sphere)}_floor{floor_size:g}_n{n}_map{size}_seed{seed}"
        img = np.asarray(r.radiance, np.float32)
        images[key] = img
        floor = (r.depth > 0) & (np.abs(np.asarray(r.position)[..., 1] + 0.5) < 1e-3)
        mean = float(img[floor].mean()) if floor.any() else float("nan")
        rows.append({"case": key, "floor_mean": mean, "image_mean": float(img.mean())})
        print(f"{key}: floor {mean:.4f} (a floor alone: 0.5 exactly)", flush=True)
    np.savez_compressed(out / "probe.npz", **images)
    report = {"adapter": gi.adapter_report(), "rows": rows}
    (out / "probe.json").write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
