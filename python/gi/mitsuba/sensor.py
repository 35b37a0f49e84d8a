"""The ``perspective`` sensor and its film: gi's camera (position, look-at, up, vertical fov,
image size). Mitsuba 3's rules: ``fov`` along ``fov_axis`` or, without ``fov``, a
``focal_length`` (35 mm film, default 50 mm) as a diagonal fov; ``hdrfilm`` (and Mitsuba
0.x's ``ldrfilm``, whose tonemapping is an output setting) width and height (768×576 by
default). A property that would change the picture and that gi cannot render (a crop
window, a principal point offset, clip planes that cut the scene) is a SceneError."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gi.mitsuba.elements import Element
from gi.mitsuba.transforms import transform

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

Props = dict[str, Element]

KNOWN = {"fov", "fov_axis", "focal_length", "to_world", "near_clip", "far_clip"}
KNOWN |= {"principal_point_offset_x", "principal_point_offset_y"}
# A pinhole's focus distance, the shutter (no motion blur in a still scene), and the
# sampler/film/filter children: no effect on the rendered radiance.
COSMETIC = frozenset({"focus_distance", "shutter_open", "shutter_close", "sampler", "film"})

FILM_KNOWN = {"width", "height", "crop_offset_x", "crop_offset_y", "crop_width", "crop_height"}
# Output encodings (gi writes its own), ldrfilm's display tonemapping, and the
# reconstruction filter (gi's pixel filter is a box): no effect on the radiance gi renders.
FILM_COSMETIC = frozenset(
    {
        "pixel_format",
        "component_format",
        "file_format",
        "banner",
        "high_quality_edges",
        "sample_border",
        "compensate",
        "gamma",
        "exposure",
        "tonemap_method",
        "key",
        "burn",
        "rfilter",
        "attach_log",
    }
)
DEFAULT_NEAR, DEFAULT_FAR = 1e-2, 1e4


def sensor(t: Translator, el: Element) -> None:
    if el.attrs.get("type") != "perspective":
        raise t.error(el, "unsupported sensor (gi reads `perspective`)")
    if t.camera is not None:
        raise t.error(el, "gi renders one sensor; this is the second")
    props = t.props(el)
    t.refuse_unknown(props, KNOWN, COSMETIC)
    for key in ("principal_point_offset_x", "principal_point_offset_y"):
        if t.float(el, props, key, 0.0) != 0.0:
            raise t.error(props[key], f"property `{key}` other than 0 is not supported")
    width, height = film_size(t, el)
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
    t.clip = (
        el,
        t.float(el, props, "near_clip", DEFAULT_NEAR),
        t.float(el, props, "far_clip", DEFAULT_FAR),
        props,
    )


def film_size(t: Translator, el: Element) -> tuple[int, int]:
    """The film's width and height (Mitsuba's default 768×576); a crop window other than
    the whole film is refused."""
    width, height = 768, 576
    for c in el.children:
        if c.tag == "film":
            if c.attrs.get("type") not in ("hdrfilm", "ldrfilm", None):
                raise t.error(c, "unsupported film (gi reads `hdrfilm` and `ldrfilm`)")
            fp = t.props(c)
            t.refuse_unknown(fp, FILM_KNOWN, FILM_COSMETIC)
            width = int(t.float(c, fp, "width", width))
            height = int(t.float(c, fp, "height", height))
            crop = [
                t.float(c, fp, "crop_offset_x", 0),
                t.float(c, fp, "crop_offset_y", 0),
                t.float(c, fp, "crop_width", width),
                t.float(c, fp, "crop_height", height),
            ]
            if crop != [0, 0, width, height]:
                key = next(k for k in fp if k.startswith("crop_"))
                raise t.error(fp[key], "a crop window is not supported (render the whole film)")
        elif c.tag not in ("sampler", "float", "integer", "string", "transform", "boolean"):
            raise t.error(c, "unsupported element in a sensor")
    return width, height


def half_height(t: Translator, el: Element, props: Props, width: int, height: int) -> float:
    """tan of half the vertical field of view (Mitsuba 3's ``parse_fov``)."""
    aspect = width / max(height, 1)
    if "fov" in props and "focal_length" in props:
        raise t.error(props["focal_length"], "give either `fov` or `focal_length`")
    if "fov" in props:
        fov = t.float(el, props, "fov", 0.0)
        axis = t.string(props, "fov_axis", "x").lower()
        if axis == "smaller":
            axis = "y" if aspect > 1 else "x"
        elif axis == "larger":
            axis = "x" if aspect > 1 else "y"
    else:
        text = t.string(props, "focal_length", "50mm").strip().removesuffix("mm")
        try:
            f = float(text)
        except ValueError:
            raise t.error(props["focal_length"], "expected a focal length like `50mm`") from None
        if not f > 0:
            raise t.error(props["focal_length"], "the focal length must be positive")
        fov = 2.0 * math.degrees(math.atan(math.hypot(36.0, 24.0) / (2.0 * f)))
        axis = "diagonal"
    half = math.tan(math.radians(fov) / 2)
    if axis == "x":
        return half / aspect
    if axis == "diagonal":
        return half * height / math.hypot(width, height)
    if axis != "y":
        raise t.error(props["fov_axis"], f"unknown fov_axis {axis!r}")
    return half


def check_clip(t: Translator) -> None:
    """Mitsuba clips what lies nearer than ``near_clip`` or farther than ``far_clip``
    (defaults 0.01 and 10⁴) along the view axis; gi's camera does not. Where a triangle may
    lie in front of the camera within the near plane's reach, or a vertex beyond the far
    plane, the picture could differ: a SceneError naming the property (its defaults when
    not given). Each object is first tested by its mesh's bounding box placed in the world
    (cheap for many instances); only objects the box does not clear are tested triangle by
    triangle (exact distance for near, vertex depth for far)."""
    if t.camera is None or t.clip is None:
        return
    el, near, far, props = t.clip
    pos = np.array(t.camera["position"])
    view = np.array(t.camera["look_at"]) - pos
    ty = math.tan(math.radians(t.camera["fov"]) / 2)
    tx = ty * t.camera["width"] / max(t.camera["height"], 1)
    reach = near * math.sqrt(1 + tx * tx + ty * ty)  # the near plane's farthest corner
    boxes: dict[str, np.ndarray] = {}
    for obj in t.objects:
        key = obj["shape"]["file"]
        v, f = t.meshes[key][:2]
        if key not in boxes:
            lo, hi = v.min(axis=0), v.max(axis=0)
            boxes[key] = np.array(
                [[(hi if b >> i & 1 else lo)[i] for i in range(3)] for b in range(8)]
            )
        m = np.array(obj["transform"]["matrix"])
        corners = boxes[key] @ m[:, :3].T + m[:, 3]
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        beyond = ((corners - pos) @ view).max() > far
        near_box = np.linalg.norm(np.clip(pos, lo, hi) - pos) < reach
        if not (beyond or near_box):
            continue
        w = v.astype(np.float64) @ m[:, :3].T + m[:, 3]
        if beyond and ((w - pos) @ view).max() > far:
            name = "far_clip"
            raise t.error(props.get(name, el), f"geometry lies beyond {name} = {far:g}")
        if near_box and (triangle_distance(w[f], pos) < reach).any():
            name = "near_clip"
            raise t.error(props.get(name, el), f"geometry lies within {name} = {near:g}")


def triangle_distance(tri: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Distance from point `p` to each triangle (n, 3, 3): the closest point found on the
    triangle's plane when it projects inside, else on its nearest edge."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    nn = np.maximum((n * n).sum(axis=1), 1e-30)
    q = p - ((p - a) * n).sum(axis=1)[:, None] * n / nn[:, None]
    inside = np.ones(len(tri), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= (np.cross(v - u, q - u) * n).sum(axis=1) >= 0
    best = np.where(inside, np.linalg.norm(p - q, axis=1), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        s = np.clip(((p - u) * e).sum(axis=1) / np.maximum((e * e).sum(axis=1), 1e-30), 0, 1)
        best = np.minimum(best, np.linalg.norm(p - (u + s[:, None] * e), axis=1))
    return best
