"""The ``perspective`` sensor and its ``hdrfilm``: gi's camera (position, look-at, up,
vertical fov, image size)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gi.mitsuba.elements import Element
from gi.mitsuba.transforms import transform

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

# `focus_distance` only matters to `thinlens`; `perspective` is a pinhole too.
KNOWN = {"fov", "fov_axis", "to_world", "near_clip", "far_clip", "focus_distance"}


def sensor(t: Translator, el: Element) -> None:
    if el.attrs.get("type") != "perspective":
        raise t.error(el, "unsupported sensor (gi reads `perspective`)")
    if t.camera is not None:
        raise t.error(el, "gi renders one sensor; this is the second")
    props = t.props(el)
    width, height = film_size(t, el)
    for key in props:
        if key not in KNOWN:
            t.notes[props[key].label] = "ignored (gi's camera is a pinhole)"
    half = half_height(t, el, props, width, height)
    m = transform(t, props.get("to_world"))
    if np.linalg.det(m[:3, :3]) < 0:
        raise t.error(props["to_world"], "mirrored sensor transforms are not supported")
    pos, d, up = m[:3, 3], m[:3, 2], m[:3, 1]
    t.camera = {
        "position": pos.tolist(),
        "look_at": (pos + d / np.linalg.norm(d)).tolist(),
        "up": up.tolist(),
        "fov": math.degrees(2 * math.atan(half)),
        "width": width,
        "height": height,
    }


def film_size(t: Translator, el: Element) -> tuple[int, int]:
    """The film's width and height (Mitsuba's default 768×576)."""
    width, height = 768, 576
    for c in el.children:
        if c.tag == "film":
            if c.attrs.get("type") not in ("hdrfilm", None):
                raise t.error(c, "unsupported film (gi reads `hdrfilm`)")
            fp = t.props(c)
            width = int(t.float(c, fp, "width", width))
            height = int(t.float(c, fp, "height", height))
        elif c.tag not in ("sampler", "float", "integer", "string", "transform", "boolean"):
            raise t.error(c, "unsupported element in a sensor")
    return width, height


def half_height(
    t: Translator, el: Element, props: dict[str, Element], width: int, height: int
) -> float:
    """tan of half the vertical field of view, from `fov` along `fov_axis`."""
    fov = t.float(el, props, "fov", 39.3077)  # Mitsuba's default: 35 mm equivalent
    axis = t.string(props, "fov_axis", "x").lower()
    aspect = width / max(height, 1)
    half = math.tan(math.radians(fov) / 2)
    if axis == "smaller":
        axis = "x" if width < height else "y"
    elif axis == "larger":
        axis = "x" if width > height else "y"
    if axis == "x":
        half /= aspect
    elif axis == "diagonal":
        half *= height / math.hypot(width, height)
    elif axis != "y":
        raise t.error(props["fov_axis"], f"unknown fov_axis {axis!r}")
    return half
