"""Light through a glass pane from each kind of source (issue 44 item 4): small scenes shared
by `tests/test_glass_sources.py` and `scripts/bench/glass_sources.py`.

`slab-*`: `tests/scenes/openings/glass_room.json` (a room, a 1.4 m glass slab 3 cm thick
floating 1.1 m over the floor); the region is the floor under the slab's middle, lit by the
source only through the glass. `area`: the room's ceiling panel; `point`: a point light in its
place.

`window-*`: `window_room.json` (a closed room with one window) with a 2 cm glass pane filling
the window; every surface inside is lit only through the pane; the region is every pixel that
sees the inside of the room (not the pane, not the sky through it). `sun`: a directional light
of the sun's size through the window; `sky`: the room's constant sky alone; `point` and
`area`: a point light and a 1 m² panel outside, 1 m from the window, facing it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import gi

DIR = Path(__file__).parent / "scenes" / "openings"
KINDS = ("slab-point", "slab-area", "window-point", "window-area", "window-sun", "window-sky")
GLASS = {"diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5}


def _slab(source: str) -> dict:
    desc = json.loads((DIR / "glass_room.json").read_text())
    if source == "point":
        desc["objects"] = [o for o in desc["objects"] if o["material"] != "lamp"]
        desc["lights"] = [{"type": "point", "position": [0.3, 2.3, -0.3], "intensity": [4] * 3}]
    return desc


def _window(source: str) -> dict:
    desc = json.loads((DIR / "window_room.json").read_text())
    desc["materials"]["glass"] = GLASS
    pane = {"shape": {"type": "box", "size": [0.02, 1.0, 1.2]}, "material": "glass"}
    desc["objects"].append(pane | {"transform": {"translate": [2.05, 1.4, 0.0]}})
    if source != "sky":
        desc.pop("environment")
    if source == "sun":
        sun = {"type": "directional", "direction": [-1.0, -0.8, 0.3], "irradiance": [6] * 3}
        desc["lights"] = [sun | {"angular_diameter": 0.53}]
    elif source == "point":
        desc["lights"] = [{"type": "point", "position": [3.05, 2.2, 0.2], "intensity": [8] * 3}]
    elif source == "area":
        desc["materials"]["lamp"] = {"diffuse": [0, 0, 0], "emission": [12] * 3}
        panel = {"shape": {"type": "quad", "size": [1.0, 1.0]}, "material": "lamp"}
        # A quad faces +y; rotated −90° about z it faces −x, towards the window.
        at = {"translate": [3.05, 2.0, 0.2], "rotate": [0, 0, 90]}
        desc["objects"].append(panel | {"transform": at})
    return desc


def scene(kind: str, width: int = 160, height: int = 120) -> gi.Scene:
    """The scene `kind` (one of KINDS) at `width` × `height`."""
    where, source = kind.split("-")
    desc = _slab(source) if where == "slab" else _window(source)
    desc["camera"] |= {"width": width, "height": height}
    return gi.Scene.from_json(json.dumps(desc), kind)


def behind(kind: str, result) -> np.ndarray:
    """The region lit by the source only through the glass (see the module's docstring)."""
    p = result.position
    if kind.startswith("slab"):
        floor = (p[..., 1] < 0.02) & (np.abs(p[..., 0] - 0.3) < 0.5)
        return (result.depth > 0) & floor & (np.abs(p[..., 2] + 0.3) < 0.5)
    return (result.depth > 0) & (p[..., 0] < 1.99)
