#!/usr/bin/env python3
"""The GPU direct light's quality on veach-mis for builds of gi (``--build NAME=DIR``, DIR a
``python/`` directory holding a built ``gi`` package), each in its own process: one frame
per seed (1-4) of `direct` (against Mitsuba's direct light, `reference-direct.exr`) and
`ispm` (against `reference.exr`) at 160×90, the measures of `tests/test_lights_veach.py`.
Prints a Markdown table for ``docs/bench/lights-gpu.md``.

    python scripts/bench/lights_veach.py --build main=/tmp/main/python --build new=python
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def worker() -> None:
    """Renders the frames with the `gi` on the path; prints one JSON line per method."""
    import warnings

    sys.path.insert(0, str(ROOT / "tests"))
    import test_lights_veach as tv
    from image_metrics import flip

    import gi

    warnings.simplefilter("ignore", gi.RenderWarning)
    scene = gi.load_scene(tv.SCENE / "scene.xml")
    lit = ~tv.sphere_mask()
    for method, file in (("direct", "reference-direct.exr"), ("ispm", "reference.exr")):
        ref = gi.read_image(tv.SCENE / file)[..., :3]
        lum = ref.mean(axis=2)
        regions = tv.highlight_regions(ref)
        rows = []
        for s in tv.SEEDS:
            img = gi.render(scene, method, size=tv.SIZE, seed=s).radiance
            rows.append(
                {
                    "mean": float(img.mean() / ref.mean()),
                    "lit": float(img[lit].mean() / ref[lit].mean()),
                    "flip": flip(ref, img),
                    "highlights": [
                        float(img.mean(axis=2)[c].sum() / lum[c].sum()) for c in regions
                    ],
                }
            )
        print(json.dumps({"method": method, "rows": rows}), flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", action="append", default=[], help="NAME=DIR (repeat)")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.worker:
        worker()
        return
    head = ["build", "method", "frame mean / Mitsuba (seeds 1-4)", "spread"]
    head += ["lit part / Mitsuba", "FLIP", "highlights (min-max)"]
    print("| " + " | ".join(head) + " |")
    print("|---|---|---|---:|---|---|---|")
    for b in a.build:
        name, _, path = b.partition("=")
        env = dict(os.environ, PYTHONPATH=os.path.abspath(path))
        out = subprocess.run(
            [sys.executable, __file__, "--worker"],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        for line in out.stdout.splitlines():
            r = json.loads(line)
            rows = r["rows"]
            mean = [x["mean"] for x in rows]
            lit = [x["lit"] for x in rows]
            fl = [x["flip"] for x in rows]
            hl = [h for x in rows for h in x["highlights"]]
            spread = max(mean) / min(mean) - 1
            print(
                f"| {name} | {r['method']} | {min(mean):.3f}-{max(mean):.3f} | {100 * spread:.1f}% "
                f"| {min(lit):.3f}-{max(lit):.3f} | {min(fl):.3f}-{max(fl):.3f} "
                f"| {min(hl):.2f}-{max(hl):.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
