"""Display transforms: linear scene radiance to display-encoded sRGB, and visible AOVs.

Tone mappers (``tonemap=``), each after scaling by ``2 ** exposure``:

- ``"clip"``: clip to [0, 1] and encode with the sRGB transfer curve (gi's original PNG
  output; highlights above 1 lose their hue).
- ``"filmic"`` (alias ``"agx"``): an AgX-style filmic curve in numpy: the AgX inset
  matrix, a log2 encoding of −12.47 to +4.03 stops around middle grey, the 6th-order
  polynomial fit of the AgX sigmoid (B. Wrensch's "minimal AgX") and the outset matrix;
  bright saturated colours desaturate towards white instead of clipping. The OpenColorIO
  configs that ship inside the PyPI OpenImageIO wheel (the ACES studio/CG configs) have
  no AgX view, hence numpy.
- ``"aces"``: the ACES 2.0 SDR (100 nits, Rec.709) output transform, applied by
  OpenColorIO through OpenImageIO's ``ociodisplay`` with OCIO's built-in default config
  (``ocio://default``), from "Linear Rec.709 (sRGB)" to the "sRGB - Display".
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from gi._checks import exposure_setting, setting_error

TONEMAPS = ("clip", "filmic", "agx", "aces")

# OCIO names in the built-in default config (ACES CG config, OCIO >= 2.2).
OCIO_CONFIG = "ocio://default"
OCIO_SOURCE = "Linear Rec.709 (sRGB)"
OCIO_DISPLAY = "sRGB - Display"
OCIO_ACES_VIEW = "ACES 2.0 - SDR 100 nits (Rec.709)"

# AgX inset/outset matrices, rows = input channels (``rgb @ M``).
_AGX_INSET = np.array(
    [
        [0.842479062253094, 0.0423282422610123, 0.0423756549057051],
        [0.0784335999999992, 0.878468636469772, 0.0784336],
        [0.0792237451477643, 0.0791661274605434, 0.879142973793104],
    ],
    dtype=np.float64,
)
_AGX_OUTSET = np.array(
    [
        [1.19687900512017, -0.0528968517574562, -0.0529716355144438],
        [-0.0980208811401368, 1.15190312990417, -0.0980434501171241],
        [-0.0990297440797205, -0.0989611768448433, 1.15107367264116],
    ],
    dtype=np.float64,
)
_AGX_MIN_EV, _AGX_MAX_EV = -12.47393, 4.026069
# 6th-order polynomial fit of the AgX base contrast sigmoid, highest power first.
_AGX_SIGMOID = (15.5, -40.14, 31.96, -6.868, 0.4298, 0.1191, -0.00232)


def check_tonemap(name: str) -> str:
    """Returns ``name`` if it is a known tone mapper, else raises :class:`gi.SettingError`
    (also a ``ValueError``)."""
    if not isinstance(name, str) or name not in TONEMAPS:
        raise setting_error(
            "tonemap", f"unknown tonemap {name!r} (use one of: {', '.join(TONEMAPS)})"
        )
    return name


def srgb_encode(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer curve (IEC 61966-2-1) of linear values in [0, 1]."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def agx(linear: np.ndarray) -> np.ndarray:
    """AgX-style filmic view of linear Rec.709 RGB (…×3): display-encoded sRGB in [0, 1]."""
    x = np.maximum(linear.astype(np.float64), 1e-10) @ _AGX_INSET
    x = np.clip(np.log2(np.maximum(x, 1e-10)), _AGX_MIN_EV, _AGX_MAX_EV)
    x = (x - _AGX_MIN_EV) / (_AGX_MAX_EV - _AGX_MIN_EV)
    x = np.polyval(_AGX_SIGMOID, x)
    # The sigmoid's output is encoded with a 2.2 power; decode, then encode as sRGB.
    x = np.power(np.clip(x @ _AGX_OUTSET, 0.0, 1.0), 2.2)
    return srgb_encode(x)


def aces(linear: np.ndarray) -> np.ndarray:
    """ACES 2.0 SDR output transform through OpenColorIO: display-encoded sRGB in [0, 1]."""
    import OpenImageIO as oiio  # noqa: N813

    img = np.ascontiguousarray(np.maximum(linear, 0.0), dtype=np.float32)
    shape = img.shape
    if img.ndim != 3:
        img = img.reshape(1, -1, 3)
    out = oiio.ImageBufAlgo.ociodisplay(
        oiio.ImageBuf(img),
        OCIO_DISPLAY,
        OCIO_ACES_VIEW,
        OCIO_SOURCE,
        colorconfig=OCIO_CONFIG,
    )
    if out.has_error:
        raise ValueError(
            "tonemap 'aces' needs OpenImageIO with OpenColorIO >= 2.2 (its built-in"
            f" config): {out.geterror()}"
        )
    return np.clip(np.asarray(out.get_pixels(oiio.FLOAT)), 0.0, 1.0).reshape(shape)


def to_display(linear: np.ndarray, tonemap: str = "clip", exposure: float = 0.0) -> np.ndarray:
    """Linear radiance (H×W×3) → display-encoded sRGB float in [0, 1]."""
    check_tonemap(tonemap)
    exposure = exposure_setting(exposure)
    x = np.nan_to_num(np.asarray(linear, dtype=np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    x = np.maximum(x, 0.0) * np.float32(2.0**exposure)
    if x.ndim == 2 or x.shape[-1] != 3:
        # One channel (or not RGB): a grey curve; only "clip" has a per-channel form.
        if tonemap == "clip":
            return srgb_encode(x).astype(np.float32)
        grey = np.repeat(x[..., :1] if x.ndim == 3 else x[..., None], 3, axis=-1)
        out = to_display(grey, tonemap)
        return out[..., 0] if x.ndim == 2 else out[..., :1]
    if tonemap == "clip":
        return srgb_encode(x).astype(np.float32)
    if tonemap in ("filmic", "agx"):
        return agx(x).astype(np.float32)
    return aces(x).astype(np.float32)


def quantize8(display: np.ndarray) -> np.ndarray:
    """Display-encoded [0, 1] floats → uint8."""
    return np.round(np.clip(display, 0.0, 1.0) * 255.0).astype(np.uint8)


def to_srgb8(linear: np.ndarray, exposure: float = 0.0, tonemap: str = "clip") -> np.ndarray:
    """Linear radiance → tone-mapped 8-bit sRGB."""
    return quantize8(to_display(linear, tonemap, exposure))


# AOVs stored as data rather than as light, and how a PNG shows them.
DATA_AOVS = ("albedo", "normal", "position", "depth")


def aov_display(
    name: str,
    image: np.ndarray,
    depth: np.ndarray | None = None,
    tonemap: str = "clip",
    exposure: float = 0.0,
) -> np.ndarray:
    """An AOV mapped to a visible [0, 1] range for 8-bit output.

    ``albedo``: clipped reflectance, sRGB-encoded. ``normal``: ``n/2 + 1/2`` per component
    (the usual normal-map colours; a miss is 0.5 grey). ``position``: each axis scaled to
    the range of the surfaces seen (misses black). ``depth``: one channel, the nearest
    surface white, the farthest 15 % grey, misses (depth 0) black. ``photons`` (ispm's
    photon-landing visualisation): scaled to its 99th percentile. Anything else is light
    (caustics, direct, indirect, …) and gets ``tonemap`` and ``exposure`` like the beauty.
    ``depth`` (the depth AOV) tells hits from misses for ``position``.
    """
    img = np.nan_to_num(np.asarray(image, dtype=np.float32))
    if name == "albedo":
        return srgb_encode(img).astype(np.float32)
    if name == "normal":
        return np.clip(img * 0.5 + 0.5, 0.0, 1.0)
    if name == "depth":
        hit = img > 0.0
        if not hit.any():
            return np.zeros_like(img)
        near, far = float(img[hit].min()), float(img[hit].max())
        t = (img - near) / max(far - near, 1e-12)
        return np.where(hit, 1.0 - 0.85 * t, 0.0).astype(np.float32)
    if name == "photons":
        # A visualisation of where photons land, in arbitrary units: scaled to its 99th
        # percentile so that it is visible whatever the photon count.
        top = float(np.percentile(img, 99.0)) if img.size else 0.0
        return srgb_encode(img / top if top > 0.0 else img).astype(np.float32)
    if name == "position":
        hit = (depth > 0.0) if depth is not None else np.any(img != 0.0, axis=-1)
        if not hit.any():
            return np.zeros_like(img)
        lo, hi = img[hit].min(axis=0), img[hit].max(axis=0)
        t = (img - lo) / np.maximum(hi - lo, 1e-12)
        return np.where(hit[..., None], t, 0.0).astype(np.float32)
    return to_display(img, tonemap, exposure)


def png_bytes(pixels: np.ndarray, compression: int = 6) -> bytes:
    """Encodes uint8 H×W (grey) or H×W×3 (RGB) pixels as a PNG file in memory, deflated
    at zlib level ``compression`` (1 fastest, 9 smallest)."""
    px = np.ascontiguousarray(pixels, dtype=np.uint8)
    if px.ndim == 3 and px.shape[2] == 1:
        px = px[:, :, 0]
    h, w = px.shape[:2]
    colour_type = 0 if px.ndim == 2 else 2
    rows = px.reshape(h, -1)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, compression))
        + chunk(b"IEND", b"")
    )
