"""Texture coordinates of a glTF material: which ``TEXCOORD_n`` set its textures read and
their ``KHR_texture_transform``.

gi reads one set of texture coordinates per triangle corner, so a material's textures
must agree on the set (``texCoord``, the extension's override included) and on the
transform; the material's primitives then carry the transformed coordinates. Textures of
one material with different sets or transforms are an error naming the texture (gi would
draw them wrongly), not a warning.

The transform is the extension's ``uv' = T(offset) · R(rotation) · S(scale) · uv`` with
``R = [[cos r, sin r], [−sin r, cos r]]`` (rotation in radians, counter-clockwise in the
image whose v runs down), in glTF's texture space, which is gi's (origin top-left).

Stored tangents follow the transform (:func:`transform_tangents`): a normal map is read in
the axes of the transformed coordinates, so the tangent frame is their derivatives
``∂P/∂(u', v') = ∂P/∂(u, v) · A⁻¹`` (``A`` the matrix's linear part); a mirroring transform
flips the handedness. MikkTSpace's tangents are generated from the transformed coordinates
and need nothing more.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gi.gltf.errors import GltfError

EXTENSION = "KHR_texture_transform"


def transform_matrix(ext: dict[str, Any], where: str) -> np.ndarray:
    """The extension's 3×3 matrix (homogeneous 2D) from its offset, rotation and scale."""
    try:
        ox, oy = (float(v) for v in ext.get("offset", [0.0, 0.0]))
        rot = float(ext.get("rotation", 0.0))
        sx, sy = (float(v) for v in ext.get("scale", [1.0, 1.0]))
    except (TypeError, ValueError) as e:
        raise GltfError(where, f"offset, rotation and scale must be numbers ({e})") from e
    if not np.isfinite([ox, oy, rot, sx, sy]).all():
        raise GltfError(where, "offset, rotation and scale must be finite")
    c, s = np.cos(rot), np.sin(rot)
    t = np.array([[1.0, 0.0, ox], [0.0, 1.0, oy], [0.0, 0.0, 1.0]])
    r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return t @ r @ np.diag([sx, sy, 1.0])


@dataclass
class MaterialUv:
    """The texture-coordinate set and transform a material's textures read, collected
    texture by texture (:meth:`add`) and checked to agree."""

    uses: list[tuple[str, int, np.ndarray | None]] = field(default_factory=list)

    def add(self, info: dict[str, Any], where: str) -> None:
        """Records texture-info ``info`` (at JSON path ``where``)."""
        ext = info.get("extensions", {}).get(EXTENSION)
        coord = info.get("texCoord", 0)
        matrix = None
        if isinstance(ext, dict):
            ew = f"{where}.extensions.{EXTENSION}"
            matrix = transform_matrix(ext, ew)
            coord = ext.get("texCoord", coord)
        if not isinstance(coord, int) or isinstance(coord, bool) or coord < 0:
            raise GltfError(f"{where}.texCoord", f"must be a set index (0, 1, ...), got {coord!r}")
        if matrix is not None and np.allclose(matrix, np.eye(3), rtol=0, atol=0):
            matrix = None
        self.uses.append((where, coord, matrix))

    def resolve(self) -> tuple[int, np.ndarray | None]:
        """The one set and transform (None: identity) the textures read; a
        :class:`GltfError` naming the first texture that disagrees with the first."""
        if not self.uses:
            return 0, None
        where0, coord0, m0 = self.uses[0]
        for where, coord, m in self.uses[1:]:
            if coord != coord0:
                raise GltfError(
                    f"{where}.texCoord",
                    f"reads TEXCOORD_{coord} but {where0} reads TEXCOORD_{coord0}: gi reads one"
                    " set of texture coordinates per material",
                )
            same = (m is None and m0 is None) or (
                m is not None and m0 is not None and np.allclose(m, m0, rtol=0, atol=1e-7)
            )
            if not same:
                raise GltfError(
                    f"{where}.extensions.{EXTENSION}",
                    f"differs from {where0}'s: gi applies one texture transform per material",
                )
        return coord0, m0


def apply(uv: np.ndarray, matrix: np.ndarray | None) -> np.ndarray:
    """Texture coordinates (N, 2) transformed by a 3×3 matrix (None: unchanged)."""
    if matrix is None:
        return uv
    return uv @ matrix[:2, :2].T + matrix[:2, 2]


def transform_tangents(
    tangents: np.ndarray, normals: np.ndarray, matrix: np.ndarray | None
) -> np.ndarray:
    """Tangents (N, 4) in gi's convention (xyz along +u, bitangent ``w · n × t`` along +v)
    for texture coordinates transformed by ``matrix`` (None: unchanged), over unit vertex
    ``normals`` (N, 3). The old frame ``(t, b)`` stands for ``(∂P/∂u, ∂P/∂v)``; the new
    tangent is ``∂P/∂u' = t · A⁻¹[0, 0] + b · A⁻¹[1, 0]`` projected on the tangent plane and
    normalized, and ``w`` is the sign that makes ``w · n × t'`` point along ``∂P/∂v'``."""
    if matrix is None:
        return tangents
    inv = np.linalg.inv(matrix[:2, :2])
    t, w = tangents[:, :3], tangents[:, 3:]
    b = w * np.cross(normals, t)
    du = t * inv[0, 0] + b * inv[1, 0]
    dv = t * inv[0, 1] + b * inv[1, 1]
    du -= normals * np.sum(du * normals, axis=1, keepdims=True)
    with np.errstate(all="ignore"):
        du = np.nan_to_num(du / np.linalg.norm(du, axis=1, keepdims=True))
    hand = np.where(np.sum(np.cross(normals, du) * dv, axis=1, keepdims=True) < 0, -1.0, 1.0)
    return np.concatenate([du, hand], axis=1)
