"""Mitsuba's ``serialized`` mesh format: a file of zlib-compressed shapes and, at its end, a
table of where each starts.

Each shape: ``uint16`` format id 0x041C, ``uint16`` version (3 or 4), then one zlib stream
holding ``uint32`` flags (0x1 vertex normals, 0x2 UVs, 0x8 vertex colours, 0x10 face
normals, 0x1000 single / 0x2000 double precision), the shape's name (version 4: UTF-8, NUL
terminated), ``uint64`` vertex and triangle counts, the positions, the normals, UVs and
colours the flags announce, and the triangles' ``uint32`` indices (``uint64`` when there are
more than 2³² vertices). The file ends with each shape's ``uint64`` offset (``uint32`` in
version 3) and a ``uint32`` shape count. All little-endian."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

MAGIC = 0x041C
HAS_NORMALS, HAS_UVS, HAS_COLORS, FACE_NORMALS = 0x1, 0x2, 0x8, 0x10
SINGLE, DOUBLE = 0x1000, 0x2000


class SerializedError(ValueError):
    """A malformed ``.serialized`` file."""


def read_serialized(
    path: Path, index: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """See :func:`_read`; a truncated or malformed file is a :class:`SerializedError`."""
    try:
        return _read(path, index)
    except (struct.error, ValueError) as e:
        if isinstance(e, SerializedError):
            raise
        raise SerializedError(f"malformed file: {e}") from None


def _read(
    path: Path, index: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Shape `index` of a serialized file: vertices, faces, normals (None where the file
    has none; an empty (0, 3) array where it asks for face normals: flat shading), UVs
    (None where it has none)."""
    data = path.read_bytes()
    if len(data) < 8:
        raise SerializedError("the file is too short")
    count = struct.unpack_from("<I", data, len(data) - 4)[0]
    if not 0 <= index < count:
        raise SerializedError(f"shape_index {index} out of range (the file holds {count})")
    magic, version = struct.unpack_from("<HH", data, 0)
    if magic != MAGIC or version not in (3, 4):
        raise SerializedError(f"not a Mitsuba serialized file (id {magic:#x}, version {version})")
    if version == 4:
        offsets = struct.unpack_from(f"<{count}Q", data, len(data) - 4 - 8 * count)
    else:
        offsets = struct.unpack_from(f"<{count}I", data, len(data) - 4 - 4 * count)
    start = offsets[index]
    magic, version = struct.unpack_from("<HH", data, start)
    if magic != MAGIC:
        raise SerializedError(f"shape {index} has no serialized header")
    try:
        body = zlib.decompressobj().decompress(data[start + 4 :])
    except zlib.error as e:
        raise SerializedError(f"shape {index}: {e}") from None
    return _shape(body, version)


def _shape(
    body: bytes, version: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    flags = struct.unpack_from("<I", body, 0)[0]
    pos = 4
    if version == 4:
        end = body.index(b"\0", pos)
        pos = end + 1
    nv, nt = struct.unpack_from("<QQ", body, pos)
    pos += 16
    real = np.float64 if flags & DOUBLE else np.float32

    def take(dtype: type, n: int) -> np.ndarray:
        nonlocal pos
        size = np.dtype(dtype).itemsize * n
        if pos + size > len(body):
            raise SerializedError("the shape's data is truncated")
        out = np.frombuffer(body, dtype=np.dtype(dtype).newbyteorder("<"), count=n, offset=pos)
        pos += size
        return out

    v = take(real, 3 * nv).reshape(-1, 3).astype(np.float64)
    n = take(real, 3 * nv).reshape(-1, 3).astype(np.float64) if flags & HAS_NORMALS else None
    uv = take(real, 2 * nv).reshape(-1, 2).astype(np.float64) if flags & HAS_UVS else None
    if flags & HAS_COLORS:
        take(real, 3 * nv)
    f = take(np.uint64 if nv > 0xFFFFFFFF else np.uint32, 3 * nt).reshape(-1, 3).astype(np.int64)
    if f.size and f.max() >= nv:
        raise SerializedError("a triangle refers to a vertex the shape does not have")
    if flags & FACE_NORMALS:
        n = np.zeros((0, 3))
    return v, f, n, uv
