"""Writes tests/scenes/openings/{window_room,glass_room}.json (issue 44 items 3-4).

window_room: a closed 4 x 2.5 x 4 m room lit only by a constant sky through a 1.2 x 1 m
window; glass_room: the same room closed, a 0.8 m ceiling panel over a 1.4 m glass slab
(3 cm thick, ior 1.5) floating 1.1 m above the floor.

    python3 scripts/data/openings_scenes.py
"""

import json
from pathlib import Path

OUT = Path(__file__).resolve().parents[2] / "tests" / "scenes" / "openings"


def box(size, at, material):
    return {
        "shape": {"type": "box", "size": size},
        "material": material,
        "transform": {"translate": at},
    }


def room(window: bool):
    """A 4 x 2.5 x 4 m room of 0.1 m walls; with `window`, a 1.2 x 1 m opening in +x."""
    objs = [
        box([4.2, 0.1, 4.2], [0, -0.05, 0], "floor"),
        box([4.2, 0.1, 4.2], [0, 2.55, 0], "white"),
        box([0.1, 2.5, 4.2], [-2.05, 1.25, 0], "white"),
        box([4.2, 2.5, 0.1], [0, 1.25, -2.05], "white"),
        box([4.2, 2.5, 0.1], [0, 1.25, 2.05], "white"),
    ]
    if window:
        objs += [
            box([0.1, 0.9, 4.2], [2.05, 0.45, 0], "white"),
            box([0.1, 0.6, 4.2], [2.05, 2.2, 0], "white"),
            box([0.1, 1.0, 1.5], [2.05, 1.4, -1.35], "white"),
            box([0.1, 1.0, 1.5], [2.05, 1.4, 1.35], "white"),
        ]
    else:
        objs.append(box([0.1, 2.5, 4.2], [2.05, 1.25, 0], "white"))
    return objs


MATERIALS = {"white": {"diffuse": [0.7, 0.7, 0.7]}, "floor": {"diffuse": [0.6, 0.55, 0.5]}}

window = {
    "camera": {
        "position": [-1.8, 1.7, 1.7],
        "look_at": [0.9, 0.3, -0.6],
        "fov": 60,
        "width": 96,
        "height": 72,
    },
    "lights": [],
    "materials": MATERIALS,
    "objects": room(True),
    "environment": {"radiance": [4.0, 4.0, 4.0]},
}

glass = {
    "camera": {
        "position": [-1.8, 1.8, 1.7],
        "look_at": [0.4, 0.2, -0.4],
        "fov": 60,
        "width": 96,
        "height": 72,
    },
    "lights": [],
    "materials": {
        **MATERIALS,
        "lamp": {"diffuse": [0, 0, 0], "emission": [12, 12, 12]},
        "glass": {"diffuse": [0, 0, 0], "transmission": [1, 1, 1], "ior": 1.5},
    },
    "objects": room(False)
    + [
        {
            "shape": {"type": "quad", "size": [0.8, 0.8]},
            "material": "lamp",
            "transform": {"translate": [0.3, 2.49, -0.3], "rotate": [180, 0, 0]},
        },
        box([1.4, 0.03, 1.4], [0.3, 1.1, -0.3], "glass"),
    ],
}

for name, desc in (("window_room", window), ("glass_room", glass)):
    with open(OUT / f"{name}.json", "w") as f:
        json.dump(desc, f, indent=1)
        f.write("\n")
