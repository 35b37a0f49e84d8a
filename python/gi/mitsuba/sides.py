"""One-sided BSDFs: Mitsuba's BSDFs reflect on the side the surface's normal faces and are
black from behind unless wrapped in ``twosided``; gi's opaque surfaces reflect on both
sides. Where that shows in the picture is refused: a planar shape (``rectangle``, ``disk``)
whose BSDF is one-sided (not ``twosided``; a shape without a BSDF gets Mitsuba's one-sided
``diffuse``) with the camera, or a point or spot light, behind its plane is a SceneError
naming the shape (Mitsuba would render its back black and absorb the light reaching it;
gi would light it). Not checked: light that reaches a back side after a bounce, and the
backs of meshes (``obj``, ``ply``, ``serialized``; closed ones show none)."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from gi.mitsuba.elements import Element

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

PLANAR = ("rectangle", "disk")


class OneSided(NamedTuple):
    """A planar shape with a one-sided BSDF: its element, a point of its plane, the unit
    normal of its reflecting side."""

    element: Element
    point: np.ndarray
    normal: np.ndarray


def note(
    t: Translator,
    el: Element,
    kind: str | None,
    bsdf: Element | None,
    flip: bool,
    m: np.ndarray,
) -> None:
    """Records shape `el` (its BSDF element `bsdf`, None for the default; placed by `m`)
    where it is planar and one-sided."""
    if kind not in PLANAR or (bsdf is not None and bsdf.attrs.get("type") == "twosided"):
        return
    normal = np.linalg.inv(m[:3, :3]).T @ np.array([0.0, 0.0, -1.0 if flip else 1.0])
    t.one_sided.append(OneSided(el, m[:3, 3].copy(), normal / np.linalg.norm(normal)))


def check(t: Translator) -> None:
    """The SceneError for the first recorded shape the camera or a point/spot light sees
    from behind."""
    viewers = [("the camera", t.camera["position"])] + [
        (f"a {light['type']} light", light["position"])
        for light in t.lights
        if light.get("type") in ("point", "spot")
    ]
    for s in t.one_sided:
        for who, pos in viewers:
            offset = float(np.dot(np.asarray(pos) - s.point, s.normal))
            if offset < -1e-6 * (1.0 + float(np.linalg.norm(np.asarray(pos) - s.point))):
                raise t.error(
                    s.element,
                    f"{who} is behind this shape's one-sided BSDF: Mitsuba renders the back "
                    "of a BSDF outside `twosided` black (and absorbs light there), gi's "
                    'surfaces are two-sided; wrap the BSDF in <bsdf type="twosided"> or turn '
                    "the shape (`flip_normals`)",
                )
