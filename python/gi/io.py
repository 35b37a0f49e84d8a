"""Image output through OpenImageIO: EXR keeps float radiance; PNG is tone-mapped sRGB."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gi import _checks


def _oiio():  # type: ignore[no-untyped-def]
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    return oiio


def to_srgb8(linear: np.ndarray, exposure: float = 0.0) -> np.ndarray:
    """Scales by 2^exposure, clips to [0, 1] and applies the sRGB transfer curve."""
    x = np.clip(np.nan_to_num(linear.astype(np.float32) * (2.0**exposure)), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(srgb * 255.0).astype(np.uint8)


FLOAT_FORMATS = {".exr", ".hdr", ".pfm", ".tif", ".tiff"}
SRGB_FORMATS = {".png", ".jpg", ".jpeg"}


def check_output(path: str | Path) -> None:
    """Raises ``ValueError`` for an unsupported format and ``OSError`` for a directory that
    cannot be written, so that a caller can check its outputs before a long render."""
    path = Path(path)
    if path.suffix.lower() not in FLOAT_FORMATS | SRGB_FORMATS:
        raise ValueError(f"unsupported image format {path.suffix!r} (use .exr or .png)")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent  # save_image creates the missing directories below it
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise OSError(f"cannot write {path}: {parent} is not a writable directory")


def save_image(path: str | Path, image: np.ndarray, exposure: float = 0.0) -> None:
    """Writes ``image`` (H×W×C or H×W float) to ``path``.

    ``.exr`` (and ``.hdr``/``.pfm``) store linear float values as they are; ``.png``/``.jpg``
    store tone-mapped 8-bit sRGB (``exposure`` in stops).
    """
    oiio = _oiio()
    path = Path(path)
    check_output(path)
    exposure = _checks.exposure_setting(exposure)
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

    def write(tmp: Path) -> None:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None:
            raise OSError(f"cannot create {path}: {oiio.geterror()}")
        spec = oiio.ImageSpec(w, h, c, fmt)
        ok = out.open(str(tmp), spec) and out.write_image(data)
        ok = out.close() and ok
        if not ok:
            raise OSError(f"cannot write {path}: {out.geterror() or 'write failed'}")

    atomic_write(path, write)


def atomic_write(path: Path, write: Callable[[Path], None]) -> None:
    """Writes ``path`` through ``write(tmp)`` into a temporary file in the same directory,
    checks that the result reads back whole, then renames it over ``path``: a failed write
    (disk full, file-size limit, Ctrl-C) raises and leaves any previous file untouched."""
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        _check_readable(tmp, path)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _check_readable(tmp: Path, path: Path) -> None:
    """Reads ``tmp`` back in full: some writers report no error when the disk is full."""
    try:
        read_image(tmp)
    except OSError as e:
        raise OSError(f"cannot write {path}: the written file does not read back ({e})") from e


def read_image(path: str | Path) -> np.ndarray:
    """Reads an image as float32 H×W×C (8-bit formats scaled to [0, 1], not linearised)."""
    oiio = _oiio()
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise OSError(f"cannot read {path}: {oiio.geterror() or 'unknown format'}")
    try:
        pixels = inp.read_image(oiio.FLOAT)
        error = inp.geterror()
    finally:
        inp.close()
    # A truncated or corrupt file reads as `None` or with an error, never as zeros.
    if pixels is None or error:
        raise OSError(f"cannot read {path}: {error or 'truncated or corrupt'}")
    arr = np.asarray(pixels, dtype=np.float32)
    return arr if arr.ndim == 3 else arr.reshape(arr.shape[0], arr.shape[1], -1)
