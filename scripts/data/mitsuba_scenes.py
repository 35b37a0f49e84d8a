"""Writes the reference scenes of issue 28 that are generated rather than written by hand
(`docs/scenes/`, see its README):

- `cornell-box/cornell-box.xml`: Mitsuba 3's own Cornell box, `mitsuba.cornell_box()`,
  written as Mitsuba XML (:func:`dict_to_xml`; Mitsuba 3.9 has no XML writer), checked by
  rendering it with Mitsuba beside the dictionary: rectangles, two cubes and an `area`
  emitter on the ceiling light.
- `sun-sky/sky.exr`: the smooth sky image of the sun-and-sky scene (128×64, equirectangular
  as Mitsuba's `envmap`).
- `emissive-room/lamp.obj` (an icosphere, the globe lamp) and `emissive-room/screen.exr`
  (the screen's radiance, up to 4 W·sr⁻¹·m⁻²) of the emissive room.

Needs Mitsuba 3 (`pip install mitsuba`; the `scalar_rgb` variant, nothing else):

    .venv/bin/python scripts/data/mitsuba_scenes.py
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "docs" / "scenes"


# Mitsuba plugin types -> their XML tag (the dictionary format infers it from the type).
TAGS = {
    "path": "integrator",
    "direct": "integrator",
    "perspective": "sensor",
    "independent": "sampler",
    "hdrfilm": "film",
    "gaussian": "rfilter",
    "box": "rfilter",
    "diffuse": "bsdf",
    "twosided": "bsdf",
    "rectangle": "shape",
    "cube": "shape",
    "sphere": "shape",
    "obj": "shape",
    "ply": "shape",
    "area": "emitter",
    "point": "emitter",
    "constant": "emitter",
}


def _number(x: float) -> str:
    return repr(float(x)) if not float(x).is_integer() else str(int(x)) + ".0"


def dict_to_xml(scene: dict, indent: str = "    ") -> str:
    """A scene in Mitsuba 3's dictionary format (as `mitsuba.load_dict` takes it) as Mitsuba
    XML: top-level keys become ids, nested plugins elements of their type's tag, `rgb` and
    `ref` dictionaries `<rgb>` and `<ref>`, transforms `<matrix>` (row-major)."""
    import mitsuba as mi

    def element(name: str | None, value, depth: int, top: bool) -> list[str]:
        pad = indent * depth
        attr = f' name="{name}"' if name and not top else ""
        if isinstance(value, dict):
            kind = value["type"]
            if kind == "rgb":
                rgb = ", ".join(_number(v) for v in value["value"])
                return [f'{pad}<rgb{attr} value="{rgb}"/>']
            if kind == "ref":
                return [f'{pad}<ref id="{value["id"]}"{attr}/>']
            if kind not in TAGS:
                raise ValueError(f"no XML tag known for plugin type {kind!r}")
            ident = f' id="{name}"' if top else attr
            inner = []
            for key, v in value.items():
                if key != "type":
                    inner += element(key, v, depth + 1, False)
            if not inner:
                return [f'{pad}<{TAGS[kind]} type="{kind}"{ident}/>']
            return [f'{pad}<{TAGS[kind]} type="{kind}"{ident}>', *inner, f"{pad}</{TAGS[kind]}>"]
        if isinstance(value, mi.ScalarTransform4f):
            # float32, as Mitsuba stores it: the shortest decimals that read back exactly.
            m = np.array(value.matrix, dtype=np.float32).reshape(4, 4)
            numbers = " ".join(str(v) for v in m.ravel())
            return [
                f"{pad}<transform{attr}>",
                f'{pad}{indent}<matrix value="{numbers}"/>',
                f"{pad}</transform>",
            ]
        if isinstance(value, bool):
            return [f'{pad}<boolean{attr} value="{str(value).lower()}"/>']
        if isinstance(value, int):
            return [f'{pad}<integer{attr} value="{value}"/>']
        if isinstance(value, float):
            return [f'{pad}<float{attr} value="{_number(value)}"/>']
        if isinstance(value, str):
            return [f'{pad}<string{attr} value="{value}"/>']
        raise ValueError(f"cannot write property {name!r} = {value!r}")

    lines = ['<?xml version="1.0" encoding="utf-8"?>', '<scene version="3.0.0">']
    for key, value in scene.items():
        if key != "type":
            lines += element(key, value, 1, True)
    return "\n".join([*lines, "</scene>"]) + "\n"


def cornell_box(out: Path) -> None:
    """`mitsuba.cornell_box()` as Mitsuba XML; checked by loading it back with Mitsuba and
    rendering it beside the dictionary (the same samples: the same image but for float
    round-off)."""
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.cornell_box()
    text = dict_to_xml(scene)
    first, rest = text.split("\n", 1)
    header = (
        f"<!-- Mitsuba 3's own Cornell box: mitsuba.cornell_box() of Mitsuba {mi.__version__},"
        "\n     written as XML by scripts/data/mitsuba_scenes.py (do not edit: run the script). -->"
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(f"{first}\n{header}\n{rest}")
    # Mitsuba's threads sum in varying order: the same scene differs by float round-off.
    a = np.array(mi.render(mi.load_dict(scene), spp=4, seed=1))
    b = np.array(mi.render(mi.load_file(str(out)), spp=4, seed=1))
    if not np.allclose(a, b, rtol=1e-4, atol=1e-5):
        raise SystemExit(f"{out} renders differently from mitsuba.cornell_box()")


def write_exr(path: Path, rgb: np.ndarray) -> None:
    """A half-float RGB EXR, zip-compressed (OpenImageIO, which gi needs anyway)."""
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    buf = oiio.ImageBuf(np.ascontiguousarray(rgb, np.float32))
    buf.specmod().attribute("compression", "zip")
    buf.set_write_format(oiio.HALF)
    if not buf.write(str(path)):
        raise SystemExit(f"cannot write {path}: {buf.geterror()}")


def smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def sky(path: Path, width: int = 128, height: int = 64) -> None:
    """A clear sky that varies slowly from texel to texel, so that Mitsuba's bilinear
    lookups and gi's constant texels show and integrate the same light (to well below the
    tests' tolerances): deeper blue at the zenith, bright at the horizon, a warm glow
    towards the sun's azimuth, grey-brown below the horizon (the ground beyond the plate),
    each blended over tens of degrees."""
    rows = (np.arange(height) + 0.5) / height  # 0 at the top (+y)
    cols = (np.arange(width) + 0.5) / width
    elevation = 90.0 - rows * 180.0  # degrees
    # Mitsuba's envmap: u grows with atan2(x, -z); the sun is towards (0.5, 1, 0.35).
    phi = cols * 2 * math.pi - math.pi
    sun_phi = math.atan2(0.5, -0.35)
    zenith = np.array([0.25, 0.42, 0.9])
    horizon = np.array([0.85, 0.9, 1.0])
    ground = np.array([0.25, 0.22, 0.2])
    up = smoothstep(elevation / 90.0)[:, None, None]
    down = smoothstep(-elevation / 30.0)[:, None, None]
    img = horizon * (1 - up) + zenith * up
    img = img * (1 - down) + ground * down
    glow = 0.35 * np.exp(-2.0 * (1 - np.cos(phi - sun_phi)))[None, :, None]
    img = img * (1 + glow * (1 - up))
    write_exr(path, np.broadcast_to(img, (height, width, 3)) * 0.8)


def lamp(path: Path) -> None:
    """An icosphere of radius 0.2 m (320 faces), outward winding, no normals."""
    import trimesh

    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.2)
    lines = ["# icosphere, radius 0.2 m, written by scripts/data/mitsuba_scenes.py"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in ball.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in ball.faces]
    path.write_text("\n".join(lines) + "\n")


def screen(path: Path, width: int = 16, height: int = 9) -> None:
    """The screen's radiance: colour bars over a dim gradient, at most 4 W·sr⁻¹·m⁻²."""
    bars = np.array(
        [[1, 1, 1], [1, 1, 0], [0, 1, 1], [0, 1, 0], [1, 0, 1], [1, 0, 0], [0, 0, 1], [0.1] * 3]
    )
    img = np.zeros((height, width, 3))
    img[:] = bars[(np.arange(width) * len(bars)) // width][None, :, :]
    img *= np.linspace(4.0, 1.0, height)[:, None, None]
    img += 0.05
    write_exr(path, img)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=SCENES, help="scene folder (docs/scenes)")
    args = ap.parse_args()
    cornell_box(args.out / "cornell-box" / "cornell-box.xml")
    sky(args.out / "sun-sky" / "sky.exr")
    lamp(args.out / "emissive-room" / "lamp.obj")
    screen(args.out / "emissive-room" / "screen.exr")
    for p in sorted(args.out.rglob("*")):
        if p.is_file():
            print(f"{p.relative_to(ROOT)}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
