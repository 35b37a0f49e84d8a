"""Camera rays, projections and picking for the viewer: which light or object lies under a
point of the image, and where a drag moves it.

Image positions are ``(x, y)`` in [0, 1] from the top-left corner; the camera is gi's
pinhole (``crates/core/src/scene/camera.rs``): ``right = forward × up``, vertical ``fov``
in degrees, the image plane at unit distance along ``forward``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

#: A light is picked when the pointer is within this fraction of the image height of it.
LIGHT_PICK_RADIUS = 0.04


@dataclass(frozen=True)
class View:
    """A camera's frame: position, unit forward/right/up, tan(fov/2) and aspect."""

    position: np.ndarray
    forward: np.ndarray
    right: np.ndarray
    up: np.ndarray
    tan_half_fov: float
    aspect: float

    @staticmethod
    def of(camera: dict[str, Any], width: int, height: int) -> View:
        """From a scene-format camera (``Renderer.describe("camera")``)."""
        p = np.asarray(camera["position"], np.float64)
        forward = _unit(np.asarray(camera["look_at"], np.float64) - p)
        right = _unit(np.cross(forward, np.asarray(camera.get("up", (0, 1, 0)), np.float64)))
        up = np.cross(right, forward)
        t = math.tan(math.radians(float(camera.get("fov", 40.0))) / 2.0)
        return View(p, forward, right, up, t, width / height)

    def ray(self, x: float, y: float) -> np.ndarray:
        """Unit direction through image position (x, y)."""
        sx = (2.0 * x - 1.0) * self.tan_half_fov * self.aspect
        sy = (1.0 - 2.0 * y) * self.tan_half_fov
        return _unit(self.forward + sx * self.right + sy * self.up)

    def project(self, point: np.ndarray) -> tuple[float, float] | None:
        """Image position of a world point; ``None`` behind the camera."""
        d = np.asarray(point, np.float64) - self.position
        z = float(d @ self.forward)
        if z <= 1e-6:
            return None
        sx = float(d @ self.right) / z / (self.tan_half_fov * self.aspect)
        sy = float(d @ self.up) / z / self.tan_half_fov
        return (sx + 1.0) / 2.0, (1.0 - sy) / 2.0

    def drag_point(self, anchor: np.ndarray, x: float, y: float) -> np.ndarray | None:
        """Where the ray through (x, y) meets the plane through ``anchor`` facing the
        camera: the point a dragged thing follows. ``None`` if the ray runs away from it."""
        d = self.ray(x, y)
        denom = float(d @ self.forward)
        dist = float((anchor - self.position) @ self.forward)
        if denom <= 1e-6 or dist <= 1e-6:
            return None
        return self.position + d * (dist / denom)


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if n == 0.0 or not math.isfinite(n):
        raise ValueError("degenerate camera")
    return v / n


def pick_light(view: View, positions: list[np.ndarray], x: float, y: float) -> int | None:
    """The light whose position is nearest to image position (x, y), within
    :data:`LIGHT_PICK_RADIUS` of the image height."""
    best, best_d = None, LIGHT_PICK_RADIUS
    for i, p in enumerate(positions):
        s = view.project(p)
        if s is None:
            continue
        d = math.hypot((s[0] - x) * view.aspect, s[1] - y)
        if d <= best_d:
            best, best_d = i, d
    return best


def intersect(
    origin: np.ndarray, direction: np.ndarray, triangles: np.ndarray
) -> tuple[float, int] | None:
    """Closest hit of a ray with triangles (T×3×3): ``(distance, triangle)`` or ``None``
    (Möller–Trumbore, both faces)."""
    if len(triangles) == 0:
        return None
    v0, e1, e2 = (
        triangles[:, 0],
        triangles[:, 1] - triangles[:, 0],
        triangles[:, 2] - triangles[:, 0],
    )
    pvec = np.cross(direction, e2)
    det = np.einsum("ij,ij->i", e1, pvec)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tvec = origin - v0
    u = np.einsum("ij,ij->i", tvec, pvec) * inv
    qvec = np.cross(tvec, e1)
    v = (qvec @ direction) * inv
    t = np.einsum("ij,ij->i", e2, qvec) * inv
    hit = ok & (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > 1e-6)
    if not hit.any():
        return None
    t = np.where(hit, t, np.inf)
    i = int(np.argmin(t))
    return float(t[i]), i


class ObjectPicker:
    """Ray picks against the scene's objects where they are now: the triangles of the
    scene as loaded, moved by each object's current transform times its loaded one's
    inverse."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, objects: list[dict[str, Any]]):
        self._triangles = np.asarray(vertices, np.float64)[np.asarray(faces, np.int64)]
        self._ranges = [tuple(o["triangles"]) for o in objects]
        self._loaded = [np.asarray(o["matrix"], np.float64) for o in objects]

    def pick(
        self, origin: np.ndarray, direction: np.ndarray, matrices: list[np.ndarray]
    ) -> tuple[int, float] | None:
        """The object hit first by the ray: ``(object index, distance)``."""
        best: tuple[int, float] | None = None
        for i, ((start, end), loaded, now) in enumerate(
            zip(self._ranges, self._loaded, matrices, strict=True)
        ):
            tris = self._triangles[start:end]
            if not np.array_equal(loaded, now):
                try:
                    m = now @ np.linalg.inv(loaded)
                except np.linalg.LinAlgError:
                    continue
                tris = tris @ m[:3, :3].T + m[:3, 3]
            hit = intersect(origin, direction, tris)
            if hit is not None and (best is None or hit[0] < best[1]):
                best = (i, hit[0])
        return best


def translated(matrix: np.ndarray, offset: np.ndarray) -> list[list[float]]:
    """``matrix`` (4×4 rows) moved by ``offset`` in world space, as rows."""
    m = np.array(matrix, np.float64)
    m[:3, 3] += offset
    return m.tolist()  # type: ignore[no-any-return]
