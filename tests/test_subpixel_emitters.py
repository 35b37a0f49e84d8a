"""Emitters smaller than a pixel in the GPU direct light (`raster/subpixel.rs`): a sphere light
0.18 px in radius in front of a dark wall gives its pixels its radiance × the area of its
projected disc (a box filter's share), in `direct` and `ispm`, and nothing where an
occluder between it and the eye hides it (the depth test against the G-buffer). Before,
no pixel centre saw it and the frame lacked its light."""

import math

import numpy as np
import pytest

import gi
from gi.scene import scene_from_desc

W, H, FOV = 48, 32, 40.0
BULB = (0.31, 0.17, 0.0)
RADIUS = 0.02
RADIANCE = 100.0


def desc(hidden: bool) -> dict:
    objects = [
        {
            "shape": {"type": "quad", "size": [8, 8]},
            "material": "grey",
            "transform": {"rotate": [90, 0, 0], "translate": [0, 0, -1]},
        },
        {
            "shape": {"type": "sphere", "radius": RADIUS, "subdivisions": 4},
            "material": "bulb",
            "transform": {"translate": list(BULB)},
        },
    ]
    if hidden:
        # A black card halfway between the eye and the bulb, ~9 px wide there.
        objects.append(
            {
                "shape": {"type": "quad", "size": [0.5, 0.5]},
                "material": "black",
                "transform": {"rotate": [90, 0, 0], "translate": [0.155, 0.085, 2.5]},
            }
        )
    return {
        "camera": {
            "position": [0, 0, 5],
            "look_at": [0, 0, 0],
            "fov": FOV,
            "width": W,
            "height": H,
        },
        "materials": {
            "grey": {"diffuse": [0.02, 0.02, 0.02]},
            "black": {"diffuse": [0, 0, 0]},
            "bulb": {"diffuse": [0, 0, 0], "emission": [RADIANCE] * 3},
        },
        "objects": objects,
    }


def window(img: np.ndarray) -> float:
    """The image's light in the 5×5 pixels around the bulb's projection."""
    f = 0.5 * H / math.tan(math.radians(FOV / 2))
    z = 5.0 - BULB[2]
    x = W / 2 + BULB[0] / z * f
    y = H / 2 - BULB[1] / z * f
    x0, y0 = int(x) - 2, int(y) - 2
    return float(img[y0 : y0 + 5, x0 : x0 + 5].mean(axis=2).sum())


def disc_light() -> float:
    """Radiance × the sphere's projected area in pixels: the disc of its solid angle
    π(r/D)² at distance D, on the image plane at angle θ off the axis (area = Ω·f²/cos³θ)."""
    f = 0.5 * H / math.tan(math.radians(FOV / 2))
    d = math.dist(BULB, (0, 0, 5))
    cos = 5.0 / d
    omega = math.pi * (RADIUS / d) ** 2
    return RADIANCE * omega * f * f / cos**3


@pytest.mark.parametrize("method", ["direct", "ispm"])
def test_sub_pixel_emitter_gives_its_cover(method, tmp_path):
    """Its light within 2% of radiance × disc area (the icosphere's silhouette is 0.2-0.5%
    inside the sphere's; the wall's own light there, lit by the bulb: albedo 0.02 × the
    bulb's irradiance 0.13 W/m² / π over 25 pixels, 0.2%; at albedo 0.5, 4.4%). Old code:
    ~0 (no pixel centre on it)."""
    img = gi.render(scene_from_desc(desc(False), "bulb.json", tmp_path), method, seed=1).radiance
    got, want = window(img), disc_light()
    print(method, "bulb's light / disc:", got / want)
    assert abs(got / want - 1) <= 0.02, (got, want)


def test_hidden_sub_pixel_emitter_adds_nothing(tmp_path):
    """Behind a black card its pixels stay dark: under 1% of its light."""
    img = gi.render(scene_from_desc(desc(True), "bulb.json", tmp_path), "direct", seed=1).radiance
    assert window(img) <= 0.01 * disc_light(), window(img)
