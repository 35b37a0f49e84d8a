"""Renders the `path` references of `tests/test_glass_sources.py` (issue 44 item 4): the
scenes of `tests/glass_scenes.py` at 64×48, each the mean of SEEDS runs of SPP samples a
pixel at the default `max_depth`, written as `tests/scenes/openings/glass-<kind>.exr` with a
JSON beside it (spp, size, the mean of the region lit only through the glass and of the
frame, and their standard errors from the spread of the seeds' means).

    python3 scripts/data/glass_sources_references.py [spp_per_seed [kind ...]]

(Committed: 1024 spp a seed, 4096 in all.)
"""

import json
import sys
from pathlib import Path

import numpy as np

import gi

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
import glass_scenes  # noqa: E402

DIR = ROOT / "tests" / "scenes" / "openings"
SEEDS = (11, 12, 13, 14)
SIZE = (64, 48)


def stderr(values: list[float]) -> float:
    return float(np.std(values, ddof=1) / np.sqrt(len(values)))


def main() -> None:
    spp = int(sys.argv[1]) if len(sys.argv) > 1 else 1024
    for kind in sys.argv[2:] or glass_scenes.KINDS:
        scene = glass_scenes.scene(kind, *SIZE)
        runs = [gi.render(scene, "path", spp=spp, seed=s) for s in SEEDS]
        region = glass_scenes.behind(kind, runs[0])
        imgs = [r.radiance[..., :3].mean(-1) for r in runs]
        img = np.mean([r.radiance[..., :3] for r in runs], axis=0).astype(np.float32)
        meta = {
            "command": f"python3 scripts/data/glass_sources_references.py {spp} {kind}",
            "spp": spp * len(SEEDS),
            "size": list(SIZE),
            "behind": float(img.mean(-1)[region].mean()),
            "behind_stderr": stderr([i[region].mean() for i in imgs]),
            "frame": float(img.mean()),
            "frame_stderr": stderr([i.mean() for i in imgs]),
        }
        gi.save_image(DIR / f"glass-{kind}.exr", img)
        (DIR / f"glass-{kind}.json").write_text(json.dumps(meta, indent=1) + "\n")
        print(kind, meta, flush=True)


if __name__ == "__main__":
    main()
