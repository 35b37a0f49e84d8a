"""Emitters: ``point``, ``spot`` and ``directional`` lights, ``area`` emitters on shapes
(the shape's material with emission), ``envmap`` and ``constant`` environments."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gi.mitsuba.bitmaps import emission_bitmap
from gi.mitsuba.elements import Element
from gi.mitsuba.transforms import transform

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

# Changes only how the light is sampled (the noise), not the picture.
COSMETIC = frozenset({"sampling_weight"})


def emitter(t: Translator, el: Element) -> None:
    """A top-level ``<emitter>``."""
    kind = el.attrs.get("type")
    if kind in ("envmap", "constant"):
        return env_emitter(t, el, kind)
    if kind == "directional":
        return directional(t, el)
    if kind == "area":
        raise t.error(el, "an area emitter belongs inside a <shape>")
    if kind not in ("point", "spot"):
        raise t.error(
            el,
            "unsupported emitter (gi reads point, spot, directional, envmap, constant and "
            "area emitters)",
        )
    props = t.props(el)
    t.refuse_unknown(
        props, {"intensity", "to_world", "position", "cutoff_angle", "beam_width"}, COSMETIC
    )
    intensity = t.color(props, "intensity", 1.0, emitter=True)
    xf = transform(t, props.get("to_world"))
    if kind == "point":
        pos = t.vec3(props["position"]) if "position" in props else xf[:3, 3]
        t.lights.append(
            {"type": "point", "position": pos.tolist(), "intensity": intensity.tolist()}
        )
        return
    cutoff = t.float(el, props, "cutoff_angle", 20.0)
    beam = t.float(el, props, "beam_width", cutoff * 0.75)
    t.notes[el.label] = (
        "Mitsuba's spot falls off linearly in angle between beam_width and cutoff_angle; "
        "gi's as a smoothstep in cos(theta) between the same angles"
    )
    t.lights.append(
        {
            "type": "spot",
            "position": xf[:3, 3].tolist(),
            "direction": xf[:3, 2].tolist(),
            "intensity": intensity.tolist(),
            "inner_angle": min(beam, cutoff),
            "outer_angle": cutoff,
        }
    )


def area_emitter(t: Translator, shape: Element, el: Element, material: str) -> str:
    """An `area` emitter on a shape: its BSDF's material with `emission` (`radiance`, a
    colour or a bitmap), one-sided (the shape's normal side) as Mitsuba's. Each emitting
    shape gets its own material, named after the shape's id or line."""
    props = t.props(el)
    t.refuse_unknown(props, {"radiance"}, COSMETIC)
    desc = dict(t.materials[material])
    p = props.get("radiance")
    if p is not None and p.tag in ("texture", "ref"):
        tex = t.resolve(p) if p.tag == "ref" else p
        desc["emission_texture"], desc["emission"] = emission_bitmap(t, tex)
    else:
        desc["emission"] = t.color(props, "radiance", 1.0, emitter=True).tolist()
    name = shape.attrs.get("id") or f"emitter@line{el.line}"
    while name in t.materials:
        name += "'"
    t.materials[name] = desc
    return name


def directional(t: Translator, el: Element) -> None:
    """`directional`: `irradiance` (W/m²) travelling along `direction`, or along
    `to_world`'s +z."""
    props = t.props(el)
    t.refuse_unknown(props, {"irradiance", "direction", "to_world"}, COSMETIC)
    if "direction" in props:
        d = t.vec3(props["direction"])
    else:
        d = transform(t, props.get("to_world"))[:3, 2]
    if not np.linalg.norm(d) > 0:
        raise t.error(el, "the direction must be non-zero")
    t.lights.append(
        {
            "type": "directional",
            "direction": (d / np.linalg.norm(d)).tolist(),
            "irradiance": t.color(props, "irradiance", 1.0, emitter=True).tolist(),
        }
    )


def env_emitter(t: Translator, el: Element, kind: str) -> None:
    """`envmap` (an equirectangular image, `scale`, a rotation about +y) or `constant`
    (`radiance`) → the scene's `environment` section."""
    if t.environment is not None:
        raise t.error(el, "a second environment emitter (gi takes one)")
    props = t.props(el)
    if kind == "constant":
        t.refuse_unknown(props, {"radiance"}, COSMETIC)
        t.environment = {"radiance": t.color(props, "radiance", 1.0, emitter=True).tolist()}
        return
    t.refuse_unknown(props, {"filename", "scale", "to_world"}, COSMETIC)
    if "filename" not in props:
        raise t.error(el, "an envmap needs a `filename`")
    name = t.string(props, "filename", "")
    from gi.environment import load_environment_image

    t.env_images[name] = load_environment_image(t.file_path(el, name), el.file or t.file, el.label)
    m = transform(t, props.get("to_world"))[:3, :3]
    cols = m / np.linalg.norm(m, axis=0)
    # gi rotates environments about +y only: to_world must be such a rotation (any uniform
    # scale is irrelevant for directions).
    if not np.allclose(cols[:, 1], [0.0, 1.0, 0.0], atol=1e-5) or abs(cols[1, 0]) > 1e-5:
        raise t.error(
            props["to_world"], "only rotations about the y axis are supported for envmaps"
        )
    rotation = math.degrees(math.atan2(cols[0, 2], cols[0, 0]))
    t.environment = {
        "file": name,
        "intensity": t.float(el, props, "scale", 1.0),
        "rotation": rotation,
    }
