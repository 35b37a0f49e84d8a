"""Image output through OpenImageIO: EXR keeps float radiance; PNG is tone-mapped sRGB."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Suffixes written as linear float images.
FLOAT_FORMATS = {".exr", ".hdr", ".pfm", ".tif", ".tiff"}
#: Suffixes written as tone-mapped 8-bit sRGB.
SRGB_FORMATS = {".png", ".jpg", ".jpeg"}


def _oiio():  # type: ignore[no-untyped-def]
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    return oiio


def to_srgb8(linear: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Scales by 2^exposure, clips to [0, 1] and applies the sRGB transfer curve."""
    x = np.clip(np.nan_to_num(linear.astype(np.float32) * (2.0**exposure)), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(srgb * 255.0).astype(np.uint8)


def save_image(path: str | Path, image: np.ndarray, exposure: float = 0.0) -> None:
    """Writes ``image`` (H×W×C or H×W float) to ``path``.

    ``.exr`` (and ``.hdr``/``.pfm``) store linear float values as they are; ``.png``/``.jpg``
    store tone-mapped 8-bit sRGB (``exposure`` in stops).
    """
    oiio = _oiio()
    path = Path(path)
    img = np.asarray(image, dtype=np.float32)
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3:
        raise ValueError(f"image must be H×W or H×W×C, got shape {img.shape}")
    if path.suffix.lower() in FLOAT_FORMATS:
        data, fmt = np.ascontiguousarray(img), "float"
    elif path.suffix.lower() in SRGB_FORMATS:
        data, fmt = np.ascontiguousarray(to_srgb8(img, exposure)), "uint8"
    else:
        raise ValueError(f"unsupported image format {path.suffix!r} (use .exr or .png)")
    h, w, c = data.shape
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    out = oiio.ImageOutput.create(str(path))
    if out is None:
        raise OSError(f"cannot create {path}: {oiio.geterror()}")
    spec = oiio.ImageSpec(w, h, c, fmt)
    try:
        if not out.open(str(path), spec) or not out.write_image(data):
            raise OSError(f"cannot write {path}: {out.geterror()}")
    finally:
        out.close()


def read_image(path: str | Path) -> np.ndarray:
    """Reads an image as float32 H×W×C (8-bit formats scaled to [0, 1], not linearised)."""
    oiio = _oiio()
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise OSError(f"cannot read {path}: {buf.geterror()}")
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
