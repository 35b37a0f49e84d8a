"""Texture images for materials: read with OpenImageIO, turned into the linear float RGBA
arrays (H, W, 4), top row first, that the core takes (``Scene.from_json(textures=...)``).

Colour maps (base colour, specular) stored as integers (PNG, JPEG, 8/16-bit TIFF) are
sRGB-decoded; float images (EXR, HDR) and data maps (roughness, normals, coverage) are used
as stored. Materials refer to textures by the names :meth:`TextureSet.add` returns.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


class TextureError(ValueError):
    """An image could not be read."""


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def read_image(path: Path) -> tuple[np.ndarray, bool]:
    """Pixels (H, W, C) as float32 in [0, 1] for integer formats, and whether the file stores
    integers (colour maps in such files are sRGB)."""
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise TextureError(f"cannot read image {path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            raise TextureError(f"cannot read image {path}: {inp.geterror()}")
        base = str(spec.format).lower()
        integer = not any(k in base for k in ("float", "half", "double"))
    finally:
        inp.close()
    img = np.asarray(pixels, dtype=np.float32)
    if img.ndim == 2:
        img = img[:, :, None]
    return img, integer


def to_rgba(img: np.ndarray, srgb: bool) -> np.ndarray:
    """(H, W, C) -> (H, W, 4): grey spreads to RGB, missing alpha is 1; sRGB decoded if asked
    (not the alpha)."""
    h, w, c = img.shape
    rgb = img[..., :3] if c >= 3 else np.repeat(img[..., :1], 3, axis=2)
    alpha = img[..., 3:4] if c >= 4 else (img[..., 1:2] if c == 2 else np.ones((h, w, 1)))
    if srgb:
        rgb = srgb_to_linear(np.clip(rgb, 0.0, None))
    out = np.concatenate([rgb, alpha], axis=2).astype(np.float32)
    return np.ascontiguousarray(np.nan_to_num(out, nan=0.0, posinf=1.0, neginf=0.0))


class TextureSet:
    """The textures of one scene, each image read once per role. A texture is named by its
    file's path relative to ``base_dir`` (the scene file's directory), in ``/`` form, as the
    scene format names it (``textures/checker.png``) however the scene's own path was
    spelled; data maps (roughness, normals, coverage) add ``#linear``."""

    def __init__(self, base_dir: Path | None = None) -> None:
        self.base_dir = base_dir
        self.arrays: dict[str, np.ndarray] = {}
        self._channels: dict[str, int] = {}

    def name(self, path: Path) -> str:
        """The name of the file ``path``: relative to ``base_dir`` (without one: as given)."""
        if self.base_dir is None:
            return str(path)
        rel = os.path.relpath(os.path.abspath(path), os.path.abspath(self.base_dir))
        return Path(rel).as_posix()

    def add(self, path: Path, colour: bool) -> str:
        """Reads ``path`` (once) as a colour map (sRGB-decoded if stored as integers) or a
        data map; returns its name. Raises :class:`TextureError`."""
        name = self.name(path)
        key = name if colour else f"{name}#linear"
        if key not in self.arrays:
            try:
                img, integer = read_image(path)
            except OSError as e:
                raise TextureError(f"cannot read image {path}: {e}") from e
            self.arrays[key] = to_rgba(img, colour and integer)
            self._channels[key] = img.shape[2]
        return key

    def channels(self, key: str) -> int:
        """Channels the image file stored."""
        return self._channels.get(key, 4)

    def add_array(self, key: str, rgba: np.ndarray) -> str:
        """A texture computed by a loader (e.g. a baked metallic-roughness combination)."""
        self.arrays[key] = np.ascontiguousarray(rgba, dtype=np.float32)
        return key


def resample(img: np.ndarray, h: int, w: int) -> np.ndarray:
    """Nearest-texel resampling to (h, w) (for combining maps of different sizes)."""
    ys = np.minimum((np.arange(h) + 0.5) * img.shape[0] / h, img.shape[0] - 1).astype(int)
    xs = np.minimum((np.arange(w) + 0.5) * img.shape[1] / w, img.shape[1] - 1).astype(int)
    return img[ys][:, xs]


def height_to_normal(height: np.ndarray, scale: float) -> np.ndarray:
    """A tangent-space normal map (RGB = (n + 1) / 2, +y up the image) from a height map,
    by central differences with repeat wrap; ``scale`` multiplies the slopes (texels)."""
    hx = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) * 0.5 * scale
    hy = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) * 0.5 * scale
    # Rows run down the image: +y in the map is -row.
    n = np.stack([-hx, hy, np.ones_like(height)], axis=2)
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    out = np.concatenate([n * 0.5 + 0.5, np.ones(height.shape + (1,))], axis=2)
    return out.astype(np.float32)
