"""What MikkTSpace costs at load: a normal-mapped UV sphere of about N triangles loaded as a
glTF scene with stored tangents (read) and without (generated per corner by MikkTSpace).

    python scripts/probe/gltf_tangents.py [--triangles 500000]

Measured 2026-12-07 (2 shared CPU cores, release build; load = reading the file, the scene
and its tangents):

| tangents | triangles | load (s) |
|---|---|---|
| stored | 500000 | 0.53 |
| MikkTSpace | 500000 | 2.99 |

MikkTSpace (bevy_mikktspace, one thread per mesh) costs about 5 µs a triangle.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))


def sphere_glb(path: Path, n: int, tangents: bool) -> Path:
    from gltf_assets import UINT, USHORT, Glb, bump_normals  # noqa: F401

    k = max(int(np.sqrt(n / 2)), 4)
    th, ph = np.meshgrid(np.linspace(0, np.pi, k + 1), np.linspace(0, 2 * np.pi, k + 1))
    pos = np.stack([np.sin(th) * np.sin(ph), np.cos(th), np.sin(th) * np.cos(ph)], -1)
    pos = pos.reshape(-1, 3).astype(np.float32)
    uv = np.stack([ph / (2 * np.pi), th / np.pi], -1).reshape(-1, 2)
    i = np.arange(k)[:, None] * (k + 1) + np.arange(k)[None, :]
    quads = np.stack([i, i + 1, i + k + 2, i + k + 1], -1).reshape(-1, 4)
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.uint32)
    g = Glb()
    attrs = {"POSITION": g.accessor(pos), "NORMAL": g.accessor(pos), "TEXCOORD_0": g.accessor(uv)}
    if tangents:
        t = np.stack([np.cos(ph), np.zeros_like(ph), -np.sin(ph)], -1).reshape(-1, 3)
        attrs["TANGENT"] = g.accessor(np.concatenate([t, np.ones((len(t), 1))], 1))
    mat = g.material({"normalTexture": {"index": g.image(bump_normals(), srgb=False)}})
    g.mesh([{"attributes": attrs, "indices": g.accessor(faces.ravel(), UINT), "material": mat}])
    return g.write(path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--triangles", type=int, default=500_000)
    args = ap.parse_args()
    import gi

    with tempfile.TemporaryDirectory() as tmp:
        print("| tangents | triangles | load (s) |\n|---|---|---|")
        for stored in (True, False):
            glb = sphere_glb(Path(tmp) / f"s{stored}.glb", args.triangles, stored)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t = time.perf_counter()
                scene = gi.load_scene(glb)
                dt = time.perf_counter() - t
            label = "stored" if stored else "MikkTSpace"
            print(f"| {label} | {scene.triangle_count} | {dt:.2f} |")


if __name__ == "__main__":
    main()
