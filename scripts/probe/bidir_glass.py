"""`bidir` behind glass (issue 44 item 4): frame means and their parts against `path`.

glass_room: tests/scenes/openings/glass_room.json (its committed `path` reference), the
floor under the slab's mean and median pixel ratio, seeds 1-2. glazed: window_room with a
2 cm glass pane in the window and a sun (irradiance 6, 0.53°) through it, with the sky
(`sky`), the sun alone (`sun`) or both (`both`); `path` 256 spp rendered here.

    python scripts/probe/bidir_glass.py glass_room
    python scripts/probe/bidir_glass.py glazed [both|sun|sky]

parts: a scene of tests/glass_scenes.py (160x120), per seed (1-4) the region lit only through
the glass: each AOV's mean over `path`'s (256 spp) region mean, and the frame's.

    python scripts/probe/bidir_glass.py parts window-sky [method]
"""

import json
import sys
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
import glass_scenes  # noqa: E402

DIR = Path(__file__).resolve().parents[2] / "tests" / "scenes" / "openings"
PARTS = ("direct", "specular", "indirect")


def parts(r, ref_mean: float) -> str:
    return " ".join(f"{n} {np.asarray(r.aov(n))[..., :3].mean() / ref_mean:.3f}" for n in PARTS)


def glass_room() -> None:
    scene = gi.load_scene(DIR / "glass_room.json")
    ref = gi.read_image(DIR / "glass_room-full.exr")[..., :3]
    for seed in (1, 2):
        r = gi.render(scene, "bidir", seed=seed)
        p, img = r.position, r.radiance[..., :3]
        under = (
            (r.depth > 0)
            & (p[..., 1] < 0.02)
            & (np.abs(p[..., 0] - 0.3) < 0.5)
            & (np.abs(p[..., 2] + 0.3) < 0.5)
        )
        a, b = img[under].mean(-1), ref[under].mean(-1)
        print(
            f"seed {seed} frame {img.mean() / ref.mean():.3f} under mean "
            f"{a.mean() / b.mean():.3f} median {np.median(a / b):.3f} | {parts(r, ref.mean())}"
        )


def glazed(keep: str) -> None:
    desc = json.loads((DIR / "window_room.json").read_text())
    desc["materials"]["glass"] = {"diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5}
    pane = {"shape": {"type": "box", "size": [0.02, 1.0, 1.2]}, "material": "glass"}
    desc["objects"].append(pane | {"transform": {"translate": [2.05, 1.4, 0.0]}})
    if keep == "sun":
        desc.pop("environment")
    sun = {"type": "directional", "direction": [-1.0, -0.8, 0.3], "irradiance": [6, 6, 6]}
    desc["lights"] = [] if keep == "sky" else [sun | {"angular_diameter": 0.53}]
    scene = gi.Scene.from_json(json.dumps(desc), f"glazed-{keep}")
    ref = gi.render(scene, "path", spp=256, seed=7).radiance[..., :3]
    for seed in (1, 2):
        r = gi.render(scene, "bidir", seed=seed)
        img = r.radiance[..., :3]
        print(f"seed {seed} frame {img.mean() / ref.mean():.3f} | {parts(r, ref.mean())}")


def region_parts(kind: str, method: str) -> None:
    scene = glass_scenes.scene(kind)
    ref = gi.render(scene, "path", spp=256, seed=7)
    region = glass_scenes.behind(kind, ref)
    b = ref.radiance[..., :3][region].mean()
    for seed in (1, 2, 3, 4):
        r = gi.render(scene, method, seed=seed)
        line = " ".join(
            f"{n} {np.asarray(r.aov(n))[..., :3][region].mean() / b:.3f}" for n in PARTS
        )
        total = r.radiance[..., :3][region].mean() / b
        print(f"seed {seed} behind {total:.3f} | {line}", flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "parts":
        region_parts(sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else "bidir")
    elif sys.argv[1] == "glass_room":
        glass_room()
    else:
        glazed(sys.argv[2] if len(sys.argv) > 2 else "both")
