"""`ispm`'s sky photons in a room lit through a window and in an open scene (issue 44 item
3), for one or more builds (each in its own process, `--build LABEL=PYTHONPATH`):

- window room (tests/scenes/openings, 96×72): one frame's image mean per seed over the
  `path` reference's, the spread (max − min over the mean) and the indirect AOV's means;
- open ground scene under the sun-sky (tests/test_environment.py's `ground_scene`, 32×32):
  the box's shadow and the lit ground (region means, channel mean) per seed and photon
  count, and the same regions of `path` (256 spp, once).

    python scripts/probe/sky_guide_scenes.py [--seeds 4] [--build LABEL=PYTHONPATH ...]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OPENINGS = ROOT / "tests/scenes/openings"


def ground_regions(result) -> tuple:
    sys.path.insert(0, str(ROOT / "tests"))
    from test_environment import region

    shadow = float(region(result, -1.4, -0.6, -0.4, 0.4).mean())
    lit = float(region(result, 0.6, 1.4, -0.4, 0.4).mean())
    return shadow, lit


def measure(seeds: int, with_path: bool) -> dict:
    import gi

    sys.path.insert(0, str(ROOT / "tests"))
    from test_environment import ground_scene

    out = {"window": [], "window_indirect": [], "ground": {}}
    window = gi.load_scene(OPENINGS / "window_room.json")
    ref = gi.read_image(OPENINGS / "window_room-full.exr")[..., :3].mean()
    for s in range(1, seeds + 1):
        r = gi.render(window, "ispm", seed=s)
        out["window"].append(float(r.radiance[..., :3].mean() / ref))
        out["window_indirect"].append(float(np.asarray(r.aov("indirect"))[..., :3].mean()))
    with tempfile.TemporaryDirectory() as tmp:
        scene = ground_scene(Path(tmp))
        for photons in (2000, 20000):
            out["ground"][photons] = [
                ground_regions(gi.render(scene, "ispm", photons=photons, seed=s))
                for s in range(1, seeds + 1)
            ]
        if with_path:
            out["path"] = ground_regions(gi.render(scene, "path", spp=256, seed=4))
    return out


def report(label: str, m: dict) -> None:
    w = np.array(m["window"])
    spread = (w.max() - w.min()) / w.mean()
    print(f"| {label} | window room ispm/path | {w.min():.3f}–{w.max():.3f} | {spread:.2%} |")
    wi = np.array(m["window_indirect"])
    print(f"| {label} | window room indirect AOV | {wi.min():.4f}–{wi.max():.4f} | |")
    for photons, regions in m["ground"].items():
        sh = np.array([r[0] for r in regions])
        lit = np.array([r[1] for r in regions])
        print(
            f"| {label} | ground {photons} photons: shadow (lit) "
            f"| {sh.min():.3f}–{sh.max():.3f} ({lit.min():.3f}–{lit.max():.3f}) | |"
        )
    if "path" in m:
        shadow, lit = m["path"]
        print(f"| path 256 spp | ground: shadow (lit) | {shadow:.3f} ({lit:.3f}) | |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--build", action="append", default=[], help="LABEL=PYTHONPATH")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--path", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        print(json.dumps(measure(a.seeds, a.path)))
        return
    builds = [b.split("=", 1) for b in a.build] or [["this", str(ROOT / "python")]]
    print(f"| build | quantity | seeds 1–{a.seeds} | spread |")
    print("|---|---|---|---|")
    for i, (label, path) in enumerate(builds):
        env = dict(os.environ, PYTHONPATH=path)
        cmd = [sys.executable, __file__, "--child", "--seeds", str(a.seeds)]
        cmd += ["--path"] if i == 0 else []
        text = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True).stdout
        report(label, json.loads(text.strip().splitlines()[-1]))


if __name__ == "__main__":
    main()
