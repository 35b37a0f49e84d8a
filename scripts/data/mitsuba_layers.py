#!/usr/bin/env python3
"""The `mask`/`normalmap`/`bumpmap` test scene (`tests/scenes/mitsuba-layers/`): its textures
and its Mitsuba 3 reference (`reference.exr`, `reference.json`).

Three unit-square rectangles side by side facing the camera (+z), each a white diffuse
BSDF inside one wrapper, in front of a grey back wall, lit by a directional light from the
upper right (+x, +y, +z):
- left: `mask` with an 8×8 checker opacity (0/1): the back wall shows through half of it;
- middle: `normalmap`, every normal tilted 30° towards +x;
- right: `bumpmap` of h = 0.05·sin(2πu) (64×64, varying along u only), scale 1.

    DRJIT_LIBLLVM_PATH=.../libLLVM-19.so .venv/bin/python scripts/data/mitsuba_layers.py
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DIR = ROOT / "tests" / "scenes" / "mitsuba-layers"
SIZE = (96, 48)
SPP, BATCHES = 1024, 4


def write_exr(path: Path, img: np.ndarray, kind: str = "float") -> None:
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    spec = oiio.ImageSpec(img.shape[1], img.shape[0], img.shape[2], kind)
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(np.ascontiguousarray(img, np.float32))
    out.close()


def textures() -> None:
    checker = (np.indices((8, 8)).sum(axis=0) % 2).astype(np.float32)[..., None]
    write_exr(DIR / "opacity.exr", checker)
    tilt = np.radians(30)
    n = np.array([np.sin(tilt), 0.0, np.cos(tilt)]) * 0.5 + 0.5
    write_exr(DIR / "normal.exr", np.broadcast_to(n, (8, 8, 3)).astype(np.float32))
    u = (np.arange(64) + 0.5) / 64
    h = 0.05 * np.sin(2 * np.pi * u)
    write_exr(DIR / "height.exr", np.broadcast_to(h, (64, 64))[..., None].astype(np.float32))


def reference(variant: str) -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    import mitsuba as mi
    from mitsuba_third_party import mitsuba_copy
    from mitsuba_third_party import write_exr as write_half

    mi.set_variant(variant)
    images = []
    t = time.perf_counter()
    for b in range(BATCHES):
        # volpath: Mitsuba's `path` integrator tests shadow rays against masked surfaces as
        # opaque (only its BSDF-sampled paths pass through the cut-out); volpath lets shadow
        # rays through null components, as gi's cut-out does.
        xml = mitsuba_copy(DIR / "scene.xml", *SIZE, SPP, seed=b, integrator="volpath")
        images.append(np.array(mi.render(mi.load_string(xml), spp=SPP, seed=b))[..., :3])
    img = np.mean(images, axis=0)
    write_half(DIR / "reference.exr", img)
    info = {
        "mitsuba": mi.__version__,
        "variant": variant,
        "size": list(SIZE),
        "spp": SPP * BATCHES,
        "integrator": "volpath",
        "mean": img.mean(axis=(0, 1)).tolist(),
        "seconds": round(time.perf_counter() - t, 1),
    }
    (DIR / "reference.json").write_text(json.dumps(info, indent=1) + "\n")
    print(json.dumps(info))


if __name__ == "__main__":
    textures()
    reference(sys.argv[1] if len(sys.argv) > 1 else "llvm_ad_rgb")
