"""Times gi.load_scene on a mesh file without normals (the docs/scene-format.md table).

    .venv/bin/python scripts/bench/bench_mesh_load.py [--baseline]

Writes an 81,920-triangle geodesic sphere, displaced like a scan, as a PLY without normals,
and a scene naming it; prints the median of 5 loads (flat, smooth, crease angle 30°).
`--baseline` also times what the loader did before (trimesh's `vertex_normals`, which needs
scipy to be fast), in the same run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import gi


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", action="store_true")
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    ball = trimesh.creation.icosphere(subdivisions=6)
    v = np.asarray(ball.vertices) * (1 + 0.02 * rng.standard_normal((len(ball.vertices), 1)))
    mesh = trimesh.Trimesh(v, ball.faces, process=False)
    with tempfile.TemporaryDirectory() as tmp:
        ply = Path(tmp) / "scan.ply"
        mesh.export(ply)
        scene = Path(tmp) / "scene.json"
        for smooth in (None, True, 30):
            obj = {"shape": {"type": "mesh", "file": "scan.ply"}, "material": "m"}
            if smooth is not None:
                obj["smooth"] = smooth
            desc = {
                "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]},
                "materials": {"m": {}},
                "objects": [obj],
            }
            scene.write_text(json.dumps(desc))
            times = []
            for _ in range(5):
                t0 = time.perf_counter()
                s = gi.load_scene(scene)
                times.append(time.perf_counter() - t0)
            what = "flat" if smooth is None else f"`smooth: {json.dumps(smooth)}`"
            print(
                f"| `gi.load_scene`, PLY without normals, {what} | {s.triangle_count} "
                f"| {statistics.median(times):.3f} s |"
            )
        if args.baseline:
            t0 = time.perf_counter()
            loaded = trimesh.load(str(ply), process=False)
            _ = loaded.vertex_normals
            dt = time.perf_counter() - t0
            has_scipy = "scipy" in sys.modules
            print(
                f"| trimesh `vertex_normals`, scipy={has_scipy} (the old loader) "
                f"| {len(loaded.faces)} | {dt:.3f} s |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
