"""What textures cost per method (the docs/bench/textures.md table).

    .venv/bin/python scripts/bench/bench_textures.py

The built-in Cornell box with every material textured: a 1024² checker as `diffuse_texture`;
then also a 1024² normal map; then also an alpha mask (`alpha_cutoff` on the checker, which
cuts nothing: every ray and fragment pays the test), against the same scene with constant
materials of the same mean albedo, in the same run: the median of 3 renders per method
(direct and ispm 128×128 at their defaults; path 64×64 at 16 spp).
"""

from __future__ import annotations

import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

import gi
from gi._gi import builtin_json
from gi.textures import srgb_to_linear

VARIANTS = ["plain", "diffuse", "+ normal map", "+ alpha mask"]


def write_png(path: Path, rgba: np.ndarray) -> None:
    out = oiio.ImageOutput.create(str(path))
    h, w, c = rgba.shape
    out.open(str(path), oiio.ImageSpec(w, h, c, oiio.UINT8))
    out.write_image(np.ascontiguousarray(np.round(np.clip(rgba, 0, 1) * 255).astype(np.uint8)))
    out.close()


def scenes(tmp: Path) -> dict[str, Path]:
    n = 1024
    idx = np.arange(n) // 64
    even = ((idx[:, None] + idx[None, :]) % 2 == 0)[..., None]
    checker = np.where(even, 0.9, 0.3) * np.ones((n, n, 4))
    checker[..., 3] = 1.0
    write_png(tmp / "checker.png", checker)
    mean = float(srgb_to_linear(np.round(checker[..., 0] * 255) / 255).mean())
    bumps = np.sin(np.arange(n) / n * 2 * np.pi * 16) * 0.3
    normal = np.stack(
        [bumps[None, :] * np.ones((n, 1)) * 0.5 + 0.5, np.full((n, n), 0.5), np.full((n, n), 0.9)],
        axis=2,
    )
    write_png(tmp / "normal.png", np.concatenate([normal, np.ones((n, n, 1))], axis=2))
    out = {}
    for name in VARIANTS:
        desc = json.loads(builtin_json("cornell"))
        for mat in desc["materials"].values():
            if name == "plain":  # the same mean albedo (photon paths as long)
                mat["diffuse"] = [c * mean for c in mat.get("diffuse", [0.8] * 3)]
            else:
                mat["diffuse_texture"] = "checker.png"
            if name in ("+ normal map", "+ alpha mask"):
                mat["normal_texture"] = "normal.png"
            if name == "+ alpha mask":
                mat["alpha_cutoff"] = 0.1
        path = tmp / f"{VARIANTS.index(name)}.json"
        path.write_text(json.dumps(desc))
        out[name] = path
    return out


def main() -> int:
    with tempfile.TemporaryDirectory() as t:
        paths = scenes(Path(t))
        runs = {
            "direct": {"size": (128, 128)},
            "ispm": {"size": (128, 128)},
            "path": {"size": (64, 64), "spp": 16},
        }
        print("| method | settings | constant | diffuse map | + normal map | + alpha mask |")
        print("|---|---|---|---|---|---|")
        for method, settings in runs.items():
            times = {}
            for name, path in paths.items():
                scene = gi.load_scene(path)
                gi.render(scene, method, **settings, seed=1)  # warm-up (pipelines, BVH)
                samples = []
                for _ in range(3):
                    t0 = time.perf_counter()
                    gi.render(scene, method, **settings, seed=1)
                    samples.append(time.perf_counter() - t0)
                times[name] = statistics.median(samples)
            desc = ", ".join(f"{k}={v}" for k, v in settings.items())
            plain = times["plain"]
            cells = [f"{plain:.3f} s"]
            cells += [f"{times[v]:.3f} s (×{times[v] / plain:.2f})" for v in VARIANTS[1:]]
            print(f"| {method} | {desc} | {' | '.join(cells)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
