#!/usr/bin/env python3
"""Renders every method on the built-in scenes (and the options that pick other code
paths: estimators, first bounce, progressive passes, temporal reuse, bidir strategies) at a
small size, and saves or compares the images bitwise.

A refactor that must leave every image unchanged runs it before (``--save DIR``) and after
(``--compare DIR``); ``--compare`` exits 1 and names every image that differs in any bit.

    scripts/ci/image_baseline.py --save /tmp/base
    scripts/ci/image_baseline.py --compare /tmp/base
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

import gi

SIZE = (40, 30)
SCENES = [
    "cornell",
    "cornell-glass",
    "cornell-anim",
    "caustic-ring",
    "mirror-shadow",
    "ring-room",
    "furnace",
]
# Per-method settings small enough for the whole matrix to run in a few minutes.
METHOD_SETTINGS: dict[str, dict[str, object]] = {
    "path": {"spp": 4, "max_depth": 6},
    "photon": {"photons": 4000, "k": 20},
    "gather": {"photons": 4000},
    "direct": {"spp": 4},
    "ispm": {"photons": 4000, "spp": 4},
    "bidir": {"spp": 4, "vpls_per_light": 8, "bundles": 4, "bundle_resolution": 32},
}
# Options that select other code paths, each rendered on two scenes.
VARIANTS: list[tuple[str, dict[str, object]]] = [
    ("ispm", {"estimator": "volumes"}),
    ("ispm", {"estimator": "tiled"}),
    ("ispm", {"estimator": "cluster"}),
    ("ispm", {"estimator": "directional"}),
    ("ispm", {"estimator": "cpu"}),
    ("ispm", {"first_bounce": "raster"}),
    ("ispm", {"footprint_volumes": True, "subsample": 1}),
    ("ispm", {"boundary_compensation": False, "caustic_density_bound": False}),
    ("ispm", {"edge_supersampling": False, "volume_shape": "quad"}),
    ("gather", {"kernel": "box", "leaf_size": 4}),
    ("photon", {"kernel": "epanechnikov", "max_radius": 0.2}),
    ("direct", {"edge_supersampling": False, "shadow_map_size": 256}),
    ("bidir", {"bidir_strategy": "vpl"}),
    ("bidir", {"bidir_strategy": "bundle", "roughness_clamping": False}),
    ("bidir", {"max_depth": 2}),
    ("path", {"light_paths": 0}),
]
VARIANT_SCENES = ["cornell", "cornell-glass"]


def cases() -> Iterator[tuple[str, str, dict[str, object]]]:
    for scene in SCENES:
        for method, settings in METHOD_SETTINGS.items():
            yield f"{scene}.{method}", scene, {"method": method, **settings}
    for i, (method, extra) in enumerate(VARIANTS):
        for scene in VARIANT_SCENES:
            yield (
                f"{scene}.{method}.v{i}",
                scene,
                {"method": method, **METHOD_SETTINGS[method], **extra},
            )


def images(result: gi.RenderResult) -> dict[str, np.ndarray]:
    out = {name: np.asarray(result.aov(name)) for name in result.aov_names()}
    return out


def render_case(scene_name: str, settings: dict[str, object]) -> dict[str, np.ndarray]:
    settings = dict(settings)
    method = str(settings.pop("method"))
    scene = gi.load_scene(scene_name)
    return images(gi.render(scene, method, size=SIZE, seed=7, **settings))


def frame_cases() -> Iterator[tuple[str, dict[str, np.ndarray]]]:
    """Renderer sequences: a moving light and object (ispm temporal reuse, bidir, direct)
    and progressive passes."""
    scene = gi.load_scene("cornell")
    for method, extra in [
        ("ispm", {"temporal_frames": 3}),
        ("ispm", {}),
        ("bidir", {}),
        ("direct", {}),
    ]:
        r = gi.Renderer(scene, method, size=SIZE, **METHOD_SETTINGS[method], **extra)
        for f in range(3):
            r.update(
                lights={0: {"position": [0.1 * f, 1.6, 0.0]}},
                objects={6: {"translate": [-0.35 + 0.05 * f, 0.6, -0.35], "rotate": [0, 20, 0]}},
            )
            yield f"frames.{method}.{len(extra)}.{f}", images(r.render(aovs=True, extras=True))
    for method in ["ispm", "gather", "path", "direct", "bidir"]:
        r = gi.Renderer(scene, method, size=SIZE, progressive=True, **METHOD_SETTINGS[method])
        for _ in range(3):
            result = r.render(aovs=True, extras=True)
        yield f"progressive.{method}", images(result)


def all_images() -> Iterator[tuple[str, dict[str, np.ndarray]]]:
    for name, scene, settings in cases():
        yield name, render_case(scene, settings)
    yield from frame_cases()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--save", type=Path, help="write the images to this folder")
    group.add_argument("--compare", type=Path, help="compare with the images in this folder")
    args = ap.parse_args()
    failures = 0
    count = 0
    for name, imgs in all_images():
        count += 1
        if args.save:
            args.save.mkdir(parents=True, exist_ok=True)
            np.savez(args.save / f"{name}.npz", **imgs)
            print(f"saved {name}", flush=True)
            continue
        ref = np.load(args.compare / f"{name}.npz")
        diffs = []
        for key in sorted(set(ref.files) | set(imgs)):
            if key not in ref.files or key not in imgs:
                diffs.append(f"{key}: only in {'new' if key in imgs else 'baseline'}")
                continue
            a, b = ref[key], imgs[key]
            if a.shape != b.shape or a.dtype != b.dtype or a.tobytes() != b.tobytes():
                detail = ""
                if a.shape == b.shape and a.size:
                    detail = f" (max |diff| {np.nanmax(np.abs(a.astype(np.float64) - b)):.3g})"
                diffs.append(f"{key}{detail}")
        if diffs:
            failures += 1
            print(f"DIFFERS {name}: {'; '.join(diffs)}", flush=True)
        else:
            print(f"equal   {name}", flush=True)
    print(f"{count} cases, {failures} differ")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
