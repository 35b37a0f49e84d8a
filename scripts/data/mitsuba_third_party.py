#!/usr/bin/env python3
"""Mitsuba 3 references of the committed third-party scenes (`tests/scenes/third_party/`):
each scene rendered by Mitsuba 3's path tracer at a small size, written beside it as
`reference.exr` with `reference.json` (spp, Mitsuba's version and variant, the image mean
per channel and its standard error over independent batches, the render time).

    DRJIT_LIBLLVM_PATH=/path/to/libLLVM-19.so \\
        .venv/bin/python scripts/data/mitsuba_third_party.py [--variant llvm_ad_rgb] [scene...]

Mitsuba reads a copy of the scene: the scene's XML as committed (its version attribute kept,
so Mitsuba's own upgrade of files older than 2.0 applies), with the sensor's film replaced
by an `hdrfilm` of the reference size with a box filter (gi's pixel filter), its sampler by
an `independent` one, and the integrator by `path` with `max_depth` = gi's 64 + 1 (Mitsuba
counts path segments, gi scattering events), and `<lookAt>` renamed `<lookat>` and
`ldrfilm` replaced, and a Mitsuba 0.x conductor's `extEta` of 1 (no effect) dropped, which
Mitsuba 3.9 refuses. `scalar_rgb` needs nothing else; the faster
`llvm_ad_rgb` needs libLLVM 19 (Debian's `libllvm19` unpacked with `dpkg -x`).

With `--direct`, the direct light alone (`max_depth` 2: emission seen and one bounce, gi's
`direct` method) into `reference-direct.exr` / `reference-direct.json`.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
THIRD_PARTY = ROOT / "tests" / "scenes" / "third_party"
# scene -> (XML file, reference width, height, spp per batch, batches)
SCENES = {
    "veach-mis": ("scene.xml", 160, 90, 1024, 4),
    "cornell-box": ("scene.xml", 128, 128, 1024, 4),
    "cbox": ("cbox.xml", 128, 128, 1024, 4),
}
MAX_DEPTH = 65


def mitsuba_copy(
    path: Path,
    width: int,
    height: int,
    spp: int,
    seed: int,
    integrator: str = "path",
    max_depth: int = MAX_DEPTH,
) -> str:
    """The scene's XML for Mitsuba at width×height (see the module doc)."""
    root = ET.parse(path).getroot()
    for el in list(root):
        if el.tag == "integrator":
            root.remove(el)
    element = ET.Element("integrator", {"type": integrator})
    ET.SubElement(element, "integer", {"name": "max_depth", "value": str(max_depth)})
    root.insert(0, element)
    for parent in root.iter():
        for el in list(parent):
            if el.get("name") == "extEta" and float(el.get("value", "1")) == 1.0:
                parent.remove(el)  # Mitsuba 0.x's outside index, 1: no effect
    for el in root.iter():
        if el.tag == "lookAt":
            el.tag = "lookat"
        if el.tag == "string" and el.get("name") == "filename":
            el.set("value", str(path.parent / el.get("value", "")))
    sensor = root.find("sensor")
    assert sensor is not None, path
    for el in list(sensor):
        if el.tag in ("film", "sampler"):
            sensor.remove(el)
    sampler = ET.SubElement(sensor, "sampler", {"type": "independent"})
    ET.SubElement(sampler, "integer", {"name": "sample_count", "value": str(spp)})
    ET.SubElement(sampler, "integer", {"name": "seed", "value": str(seed)})
    film = ET.SubElement(sensor, "film", {"type": "hdrfilm"})
    ET.SubElement(film, "integer", {"name": "width", "value": str(width)})
    ET.SubElement(film, "integer", {"name": "height", "value": str(height)})
    ET.SubElement(film, "rfilter", {"type": "box"})
    return ET.tostring(root, encoding="unicode")


def render(name: str, variant: str, direct: bool = False) -> None:
    import mitsuba as mi

    mi.set_variant(variant)
    file, width, height, spp, batches = SCENES[name]
    depth = 2 if direct else MAX_DEPTH
    stem = "reference-direct" if direct else "reference"
    path = THIRD_PARTY / name / file
    images = []
    t = time.perf_counter()
    for b in range(batches):
        scene = mi.load_string(mitsuba_copy(path, width, height, spp, seed=b, max_depth=depth))
        images.append(np.array(mi.render(scene, spp=spp, seed=b), np.float64)[..., :3])
    seconds = time.perf_counter() - t
    img = np.mean(images, axis=0)
    means = np.array([i.mean(axis=(0, 1)) for i in images])
    info = {
        "mitsuba": mi.__version__,
        "variant": variant,
        "size": [width, height],
        "spp": spp * batches,
        "max_depth": depth,
        "rfilter": "box",
        "mean": img.mean(axis=(0, 1)).tolist(),
        "stderr": (means.std(axis=0, ddof=1) / np.sqrt(batches)).tolist(),
        "seconds": round(seconds, 1),
    }
    write_exr(THIRD_PARTY / name / f"{stem}.exr", img)
    (THIRD_PARTY / name / f"{stem}.json").write_text(json.dumps(info, indent=1) + "\n")
    print(name, json.dumps(info), flush=True)


def write_exr(path: Path, img: np.ndarray) -> None:
    """A half-float RGB EXR, zip-compressed (small; the test compares means at 2%)."""
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    spec = oiio.ImageSpec(img.shape[1], img.shape[0], 3, "half")
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(np.ascontiguousarray(img, np.float32))
    out.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--direct", action="store_true", help="direct light only (max_depth 2)")
    args = ap.parse_args()
    for name in args.scenes:
        if name not in SCENES:
            sys.exit(f"unknown scene {name!r} (known: {', '.join(SCENES)})")
        render(name, args.variant, args.direct)


if __name__ == "__main__":
    main()
