"""``<transform>``: translate, scale, rotate, matrix and lookat operations, composed in
document order (each applied after the ones before it)."""

from __future__ import annotations

import math

import numpy as np

from gi.mitsuba.elements import Element
from gi.mitsuba.values import Reader


def coordinate_system(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit vector ``n`` to an orthonormal basis, as Mitsuba
    3's ``coordinate_system`` builds them (Duff et al. 2017, "Building an orthonormal basis,
    revisited"): what its ``<lookat>`` takes as ``up`` when none is given."""
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return s, t


def transform(r: Reader, el: Element | None) -> np.ndarray:
    """The 4×4 matrix of a ``<transform>`` (identity for none)."""
    m = np.eye(4)
    if el is None:
        return m
    if el.tag != "transform":
        raise r.error(el, "expected a <transform>")
    for op in el.children:
        m = transform_op(r, op) @ m
    return m


def transform_op(r: Reader, op: Element) -> np.ndarray:
    t = np.eye(4)
    if op.tag == "translate":
        t[:3, 3] = r.vec3(op)
    elif op.tag == "scale":
        if "value" in op.attrs:
            s = r.vec3(op)
        else:
            s = np.array([r.numbers(op, r.attr(op, k, "1"), 1)[0] for k in "xyz"])
        t[:3, :3] = np.diag(s)
    elif op.tag == "rotate":
        t[:3, :3] = rotation(r, op)
    elif op.tag == "matrix":
        v = r.numbers(op, r.attr(op, "value"))
        if len(v) == 16:
            t = np.array(v).reshape(4, 4)
        elif len(v) == 9:
            t[:3, :3] = np.array(v).reshape(3, 3)
        else:
            raise r.error(op, "expected 9 or 16 numbers")
    elif op.tag == "lookat":
        t = lookat(r, op)
    else:
        raise r.error(op, "unknown transform operation")
    return t


def rotation(r: Reader, op: Element) -> np.ndarray:
    """``<rotate>``: `angle` degrees about the axis (`x`/`y`/`z` or `value`)."""
    axis = r.vec3(op)
    angle = math.radians(r.numbers(op, r.attr(op, "angle"), 1)[0])
    n = np.linalg.norm(axis)
    if n == 0:
        raise r.error(op, "rotation axis must be non-zero")
    x, y, z = axis / n
    c, s = math.cos(angle), math.sin(angle)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def lookat(r: Reader, op: Element) -> np.ndarray:
    """``<lookat origin target up>``: +z towards the target, +y up, +x left."""
    t = np.eye(4)
    origin = np.array(r.numbers(op, r.attr(op, "origin"), 3))
    target = np.array(r.numbers(op, r.attr(op, "target"), 3))
    up = np.array(r.numbers(op, r.attr(op, "up", "0, 0, 0"), 3))
    d = target - origin
    if np.linalg.norm(d) == 0:
        raise r.error(op, "origin and target must differ")
    d /= np.linalg.norm(d)
    if not up.any():
        # No `up` (or a zero one): Mitsuba 3 takes one perpendicular to the view.
        up = coordinate_system(d)[0]
    left = np.cross(up, d)
    if np.linalg.norm(left) < 1e-9:
        raise r.error(op, "up must not be parallel to the viewing direction")
    left /= np.linalg.norm(left)
    t[:3, 0], t[:3, 1], t[:3, 2], t[:3, 3] = left, np.cross(d, left), d, origin
    return t
