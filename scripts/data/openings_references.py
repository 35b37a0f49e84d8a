"""Renders the `path` references of tests/scenes/openings (issue 44 items 3-4): per scene
the direct light alone (`max_depth` 1) and the full light, each the mean of SEEDS runs of
SPP samples a pixel at the scene's own size, written as `<scene>-<part>.exr` with a JSON
beside it (spp, max_depth, size, the mean per channel and its standard error from the
spread of the seeds' means).

    python3 scripts/data/openings_references.py [spp_per_seed [scene-part ...]]

(window_room-direct, window_room-full and glass_room-direct at 1024 spp a seed,
glass_room-full at 512: 2048 spp, its mean's standard error 0.1%.)
"""

import json
import sys
from pathlib import Path

import numpy as np

import gi

DIR = Path(__file__).resolve().parents[2] / "tests" / "scenes" / "openings"
SEEDS = (11, 12, 13, 14)
PARTS = {"direct": 1, "full": 64}


def main() -> None:
    spp = int(sys.argv[1]) if len(sys.argv) > 1 else 1024
    only = set(sys.argv[2:])
    for name in ("window_room", "glass_room"):
        scene = gi.load_scene(DIR / f"{name}.json")
        for part, depth in PARTS.items():
            if only and f"{name}-{part}" not in only:
                continue
            runs = [
                gi.render(scene, "path", spp=spp, seed=s, max_depth=depth).radiance[..., :3]
                for s in SEEDS
            ]
            img = np.mean(runs, axis=0).astype(np.float32)
            means = np.array([r.reshape(-1, 3).mean(0) for r in runs])
            meta = {
                "command": f"python3 scripts/data/openings_references.py {spp} {name}-{part}",
                "spp": spp * len(SEEDS),
                "max_depth": depth,
                "size": [img.shape[1], img.shape[0]],
                "mean": img.reshape(-1, 3).mean(0).tolist(),
                "stderr": (means.std(0, ddof=1) / np.sqrt(len(SEEDS))).tolist(),
            }
            gi.save_image(DIR / f"{name}-{part}.exr", img)
            (DIR / f"{name}-{part}.json").write_text(json.dumps(meta, indent=1) + "\n")
            print(name, part, meta["mean"], meta["stderr"], flush=True)


if __name__ == "__main__":
    main()
