#!/usr/bin/env python3
"""Single-material spheres (`tests/scenes/mitsuba-materials/<name>.xml`) and their Mitsuba 3
references (`<name>.exr`, `references.json`): one sphere per BSDF that branch `materials`
brings (plastic, roughplastic GGX and Beckmann, conductor and roughconductor with named
metals, roughdielectric), on a grey floor under a rectangular area light and a dim constant
sky, 64×64.

    DRJIT_LIBLLVM_PATH=.../libLLVM-19.so .venv/bin/python scripts/data/mitsuba_materials.py
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DIR = ROOT / "tests" / "scenes" / "mitsuba-materials"
SIZE, SPP, BATCHES = 64, 1024, 4
BSDFS = {
    "plastic": '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5, 0.2, 0.1"/>'
    '<float name="int_ior" value="1.5"/></bsdf>',
    "roughplastic-ggx": '<bsdf type="roughplastic"><string name="distribution" value="ggx"/>'
    '<rgb name="diffuse_reflectance" value="0.5, 0.2, 0.1"/><float name="alpha" value="0.1"/>'
    "</bsdf>",
    "roughplastic-beckmann": '<bsdf type="roughplastic">'
    '<string name="distribution" value="beckmann"/>'
    '<rgb name="diffuse_reflectance" value="0.5, 0.2, 0.1"/><float name="alpha" value="0.1"/>'
    "</bsdf>",
    "conductor-au": '<bsdf type="conductor"><string name="material" value="Au"/></bsdf>',
    "roughconductor-cu": '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
    '<float name="alpha" value="0.2"/></bsdf>',
    "roughdielectric": '<bsdf type="roughdielectric"><float name="alpha" value="0.1"/>'
    '<float name="int_ior" value="1.5"/></bsdf>',
}
SCENE = """<scene version="3.0.0">
    <!-- scripts/data/mitsuba_materials.py -->
    <sensor type="perspective">
        <float name="fov" value="35"/>
        <transform name="to_world">
            <lookat origin="0, 1.5, 5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="{size}"/>
            <integer name="height" value="{size}"/>
        </film>
    </sensor>
    <shape type="sphere">
        {bsdf}
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="10"/>
            <rotate x="1" angle="-90"/>
            <translate y="-1"/>
        </transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.4, 0.4, 0.4"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="1.5"/>
            <rotate x="1" angle="90"/>
            <translate x="1" y="4" z="1"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.2, 0.2, 0.2"/></emitter>
</scene>
"""


def main() -> None:
    sys.path.insert(0, str(Path(__file__).parent))
    import mitsuba as mi
    from mitsuba_third_party import mitsuba_copy, write_exr

    mi.set_variant(sys.argv[1] if len(sys.argv) > 1 else "llvm_ad_rgb")
    meta = {}
    for name, bsdf in BSDFS.items():
        path = DIR / f"{name}.xml"
        path.write_text(SCENE.format(size=SIZE, bsdf=bsdf))
        t = time.perf_counter()
        images = []
        for b in range(BATCHES):
            xml = mitsuba_copy(path, SIZE, SIZE, SPP, seed=b)
            images.append(np.array(mi.render(mi.load_string(xml), spp=SPP, seed=b))[..., :3])
        img = np.mean(images, axis=0)
        means = np.array([i.mean(axis=(0, 1)) for i in images])
        write_exr(DIR / f"{name}.exr", img)
        meta[name] = {
            "mean": img.mean(axis=(0, 1)).tolist(),
            "stderr": (means.std(axis=0, ddof=1) / np.sqrt(BATCHES)).tolist(),
            "seconds": round(time.perf_counter() - t, 1),
        }
        print(name, json.dumps(meta[name]), flush=True)
    info = {
        "mitsuba": mi.__version__,
        "size": [SIZE, SIZE],
        "spp": SPP * BATCHES,
        "max_depth": 65,
        "rfilter": "box",
        "scenes": meta,
    }
    (DIR / "references.json").write_text(json.dumps(info, indent=1) + "\n")


if __name__ == "__main__":
    main()
