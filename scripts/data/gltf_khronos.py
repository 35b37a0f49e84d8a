"""Khronos glTF sample models in the corpus of ``tests/scenes/gltf/``, reduced to a few
hundred kB, and their Blender Cycles references.

From a checkout of the Khronos glTF-Sample-Assets repository (its ``Models/`` folder, given
as ``--source``) this writes ``tests/scenes/gltf/khronos/MODEL/``: the model (textures
downscaled to at most 256 px and the whole packed as one ``.glb``; small models unchanged)
beside the model's upstream ``LICENSE.md`` and ``README.md`` and a ``CHANGES.md`` saying
what was changed. It writes a horizon sky (``khronos/horizon.exr``: an equirectangular
image that varies with elevation only, so that the two renderers' conventions for the
azimuth cannot differ) and a gi scene per model (``tests/scenes/gltf/NAME.json``: the model,
a camera, the horizon sky and the sun of the other corpus scenes; DamagedHelmet the sky
alone, as the issue shows it). With ``--cycles`` it
renders Cycles' image of each scene (``NAME.cycles.exr``, as ``gltf_corpus.py`` does, the
sky as an Environment Texture and the material textures with closest-texel lookup, as gi
reads them: Cycles' default interpolates 8-bit sRGB texels before decoding them; the
Principled BSDF with single-scattering GGX, gi's microfacet model: Cycles' default
Multiscatter GGX keeps the light of a rough dielectric that single scattering loses, 2.4%
and 3.2% of the Box images' means).

    python scripts/data/gltf_khronos.py --source glTF-Sample-Assets/Models [--cycles]
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import struct
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio  # noqa: N813

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "tests" / "scenes" / "gltf"
KHRONOS = OUT / "khronos"
sys.path.insert(0, str(Path(__file__).parent))

from gltf_corpus import SIZE, SUN, SUN_IRRADIANCE, render_cycles  # noqa: E402

MAX_TEXTURE = 256


def models() -> dict[str, dict]:
    """Scene name -> the model's folder, the upstream file, how it is reduced, the camera
    (gi's y-up frame) and, for Cycles, an uncompressed twin of a Draco file."""
    return {
        "khronos_damaged_helmet": {
            "model": "DamagedHelmet",
            "source": "glTF/DamagedHelmet.gltf",
            "pack": True,
            "camera": ([0.0, 0.0, 3.4], 40.0),
            # Lit as the must-show: by an environment alone.
            "sun": False,
        },
        "khronos_normal_tangent_mirror": {
            "model": "NormalTangentMirrorTest",
            "source": "glTF/NormalTangentMirrorTest.gltf",
            "pack": True,
            "camera": ([0.0, 0.0, 3.6], 45.0),
        },
        "khronos_box_draco": {
            "model": "Box",
            "source": "glTF-Draco/Box.gltf",
            "files": ["glTF-Draco/Box.bin", "glTF-Binary/Box.glb"],
            "cycles_twin": "Box.glb",
            "camera": ([2.4, 1.8, 3.2], 32.0),
        },
        "khronos_box_textured": {
            "model": "BoxTextured",
            "source": "glTF-Binary/BoxTextured.glb",
            "camera": ([2.4, 1.8, 3.2], 32.0),
        },
    }


def horizon_sky(width: int = 64, height: int = 32) -> np.ndarray:
    """An equirectangular sky (rows: elevation from +90° to −90°) that depends on the row
    only: a blue-white sky brightening towards the horizon, then a dark brown ground."""
    elev = 90.0 - (np.arange(height) + 0.5) * 180.0 / height
    sky = np.array([0.35, 0.45, 0.7])[None, :] + 0.4 * (1 - np.sin(np.radians(elev)))[:, None]
    ground = np.tile([0.12, 0.09, 0.06], (height, 1))
    rows = np.where((elev > 0)[:, None], sky, ground)
    return np.repeat(rows[:, None, :], width, axis=1).astype(np.float32)


def write_exr(path: Path, img: np.ndarray) -> None:
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], img.shape[2], oiio.FLOAT)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(img)
    out.close()


def reduced_image(path: Path) -> tuple[bytes, str]:
    """The image at ``path`` downscaled to at most MAX_TEXTURE px a side (its format kept),
    as file bytes and MIME type."""
    buf = oiio.ImageBuf(str(path))
    w, h = buf.spec().width, buf.spec().height
    scale = min(1.0, MAX_TEXTURE / max(w, h))
    if scale < 1.0:
        roi = oiio.ROI(0, max(1, round(w * scale)), 0, max(1, round(h * scale)), 0, 1, 0, 4)
        buf = oiio.ImageBufAlgo.resize(buf, roi=roi)
    jpeg = path.suffix.lower() in (".jpg", ".jpeg")
    tmp = Path("/tmp") / f"gi-khronos-{path.stem}{'.jpg' if jpeg else '.png'}"
    if jpeg:
        buf.specmod().attribute("Compression", "jpeg:90")
    buf.write(str(tmp))
    data = tmp.read_bytes()
    tmp.unlink()
    return data, "image/jpeg" if jpeg else "image/png"


def pack_glb(gltf: Path, out: Path) -> None:
    """The .gltf at ``gltf`` (one external buffer, external images) packed as one .glb with
    its images reduced (:func:`reduced_image`) and stored in the binary chunk."""
    doc = json.loads(gltf.read_text())
    (buffer,) = doc["buffers"]
    blob = bytearray((gltf.parent / buffer["uri"]).read_bytes())
    for image in doc.get("images", []):
        data, mime = reduced_image(gltf.parent / image.pop("uri"))
        blob += b"\0" * (-len(blob) % 4)
        doc["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        image["bufferView"] = len(doc["bufferViews"]) - 1
        image["mimeType"] = mime
        blob += data
    blob += b"\0" * (-len(blob) % 4)
    doc["buffers"] = [{"byteLength": len(blob)}]
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
    chunks += struct.pack("<II", len(blob), 0x004E4942) + bytes(blob)
    out.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)


CHANGES = {
    True: (
        "Changed for gi's test corpus (CC BY 4.0 allows adaptations with attribution): the "
        "textures downscaled to at most {n} px a side (OpenImageIO's resize; JPEG textures "
        "re-encoded at quality 90) and the model packed from its `glTF/` form into one "
        "binary `.glb`; the geometry, materials and node tree are unchanged.\n"
    ),
    False: "Unchanged copies of the upstream files listed below.\n",
}


def write_model(name: str, spec: dict, source: Path) -> Path:
    """The model's reduced or copied files under ``khronos/MODEL/`` and its licence notes;
    the path of the file the scene names."""
    src, dst = source / spec["model"], KHRONOS / spec["model"]
    dst.mkdir(parents=True, exist_ok=True)
    for note in ("LICENSE.md", "README.md"):
        shutil.copy(src / note, dst / note)
    if spec.get("pack"):
        out = dst / f"{spec['model']}.glb"
        pack_glb(src / spec["source"], out)
        kept = [spec["source"]]
    else:
        kept = [spec["source"], *spec.get("files", [])]
        for f in kept:
            shutil.copy(src / f, dst / Path(f).name)
        out = dst / Path(spec["source"]).name
    listing = "".join(f"- upstream `Models/{spec['model']}/{f}`\n" for f in kept)
    (dst / "CHANGES.md").write_text(
        f"# {spec['model']} in gi's corpus\n\nFrom the Khronos glTF-Sample-Assets repository; "
        "licence and credits in `LICENSE.md` and `README.md` beside this file (upstream's).\n\n"
        + CHANGES[bool(spec.get("pack"))].format(n=MAX_TEXTURE)
        + "\n"
        + listing
    )
    return out


def write_scene(name: str, spec: dict, asset: Path) -> None:
    position, fov = spec["camera"]
    n = math.sqrt(sum(x * x for x in SUN))
    scene = {
        "camera": {
            "position": position,
            "look_at": [0, 0, 0],
            "fov": fov,
            "width": SIZE,
            "height": SIZE,
        },
        "lights": [
            {
                "type": "directional",
                "direction": [-x / n for x in SUN],
                "irradiance": [SUN_IRRADIANCE] * 3,
            }
        ]
        if spec.get("sun", True)
        else [],
        "environment": {"file": "khronos/horizon.exr"},
        "objects": [{"shape": {"type": "mesh", "file": str(asset.relative_to(OUT))}}],
    }
    (OUT / f"{name}.json").write_text(json.dumps(scene, indent=1) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--source", type=Path, required=True, help="glTF-Sample-Assets/Models")
    ap.add_argument("--cycles", action="store_true", help="also render Cycles' references")
    ap.add_argument("--samples", type=int, default=1024)
    ap.add_argument("--only", nargs="*", help="scene names to write (default: all)")
    args = ap.parse_args()
    KHRONOS.mkdir(parents=True, exist_ok=True)
    write_exr(KHRONOS / "horizon.exr", horizon_sky())
    for name, spec in models().items():
        if args.only and name not in args.only:
            continue
        asset = write_model(name, spec, args.source)
        write_scene(name, spec, asset)
        if args.cycles:
            scene = json.loads((OUT / f"{name}.json").read_text())
            twin = asset.parent / spec.get("cycles_twin", asset.name)
            render_cycles(name, scene, twin, args.samples, closest_texels=True, single_scatter=True)


if __name__ == "__main__":
    main()
