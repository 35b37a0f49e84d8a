"""Image output through OpenImageIO.

``.exr`` keeps float radiance and holds every requested AOV as named layers in one file;
``.hdr``/``.pfm``/``.tif`` keep float values, one image per file; ``.png``/``.jpg`` are
8-bit sRGB through a display transform (see :mod:`gi.display`). Files are written to a
temporary name beside the target and renamed into place, so a failed write leaves no
partial file.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gi import _checks, display

if TYPE_CHECKING:
    from gi.render import RenderResult

#: Suffixes holding several AOVs as layers of one file.
LAYERED_FORMATS = {".exr"}
#: Suffixes written as linear float images.
FLOAT_FORMATS = {".exr", ".hdr", ".pfm", ".tif", ".tiff"}
#: Suffixes written as 8-bit sRGB through a display transform.
SRGB_FORMATS = {".png", ".jpg", ".jpeg"}


def _oiio():  # type: ignore[no-untyped-def]
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    return oiio


def to_srgb8(linear: np.ndarray, exposure: float = 0.0, tonemap: str = "clip") -> np.ndarray:
    """Scales by 2^exposure, applies ``tonemap`` and returns 8-bit sRGB."""
    return display.to_srgb8(linear, exposure, tonemap)


def channel_names(aov: str, channels: int) -> list[str]:
    """EXR channel names of an AOV: the beauty is ``R, G, B``; ``normal`` is ``N.X…``,
    ``position`` ``P.X…``, ``depth`` ``Z``; any other AOV ``NAME.R, NAME.G, NAME.B``."""
    if aov == "depth" and channels == 1:
        return ["Z"]
    if channels == 1:
        return [f"{aov}.Y"]
    if aov == "radiance":
        return ["R", "G", "B"][:channels]
    if aov in ("normal", "position"):
        return [f"{aov[0].upper()}.{c}" for c in "XYZ"][:channels]
    return [f"{aov}.{c}" for c in "RGB"][:channels]


def check_output_path(path: str | Path) -> Path:
    """Checks that ``path`` has a supported extension and can be written, without writing.

    Raises ``ValueError`` for an unknown format and ``OSError`` for a path that is a
    directory or lies in a directory that cannot be created or written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FLOAT_FORMATS | SRGB_FORMATS:
        known = ", ".join(sorted(FLOAT_FORMATS | SRGB_FORMATS))
        raise ValueError(f"unsupported image format {path.suffix!r} for {path} (use {known})")
    return check_writable(path)


def check_writable(path: str | Path) -> Path:
    """Raises ``OSError`` if ``path`` is a directory or lies in a directory that cannot be
    created or written; writes nothing."""
    path = Path(path)
    if path.is_dir():
        raise OSError(f"cannot write {path}: it is a directory")
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise OSError(f"cannot write {path}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OSError(f"cannot write {path}: {parent} is not writable")
    return path


def _write(
    path: Path,
    data: np.ndarray,
    fmt: str,
    names: list[str] | None = None,
    attributes: Mapping[str, str | int | float] | None = None,
) -> None:
    """Writes H×W×C ``data`` atomically (temporary file, then rename)."""
    oiio = _oiio()
    h, w, c = data.shape
    path.parent.mkdir(parents=True, exist_ok=True)
    out = oiio.ImageOutput.create(str(path))
    if out is None:
        raise OSError(f"cannot create {path}: {oiio.geterror()}")
    spec = oiio.ImageSpec(w, h, c, fmt)
    if names is not None:
        spec.channelnames = tuple(names)
    for key, value in (attributes or {}).items():
        spec.attribute(key, value)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        try:
            ok = out.open(str(tmp), spec) and out.write_image(np.ascontiguousarray(data))
            if not ok:
                raise OSError(f"cannot write {path}: {out.geterror()}")
        finally:
            closed = out.close()
        if not closed:
            raise OSError(f"cannot write {path}: {out.geterror() or 'closing failed'}")
        # Read back in full: libpng reports no error for a short write (disk full, a
        # file-size limit), which would otherwise replace a good file with a truncated one.
        try:
            read_image(tmp)
        except OSError as e:
            raise OSError(f"cannot write {path}: the written file does not read back ({e})") from e
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def save_image(
    path: str | Path, image: np.ndarray, exposure: float = 0.0, tonemap: str = "clip"
) -> None:
    """Writes ``image`` (H×W×C or H×W float) to ``path``.

    ``.exr`` (and ``.hdr``/``.pfm``/``.tif``) store linear float values as they are;
    ``.png``/``.jpg`` store 8-bit sRGB through ``tonemap`` (see :mod:`gi.display`) after
    ``exposure`` stops.
    """
    path = check_output_path(path)
    display.check_tonemap(tonemap)
    exposure = _checks.exposure_setting(exposure)
    img = np.asarray(image, dtype=np.float32)
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3:
        raise ValueError(f"image must be H×W or H×W×C, got shape {img.shape}")
    if path.suffix.lower() in FLOAT_FORMATS:
        _write(path, img, "float")
    else:
        _write(path, display.to_srgb8(img, exposure, tonemap), "uint8")


def save_layers(
    path: str | Path,
    layers: Mapping[str, np.ndarray],
    attributes: Mapping[str, str | int | float] | None = None,
) -> list[str]:
    """Writes named float images into one multichannel EXR; returns its channel names.

    ``layers`` maps AOV names to H×W×3 or H×W arrays of one size; channels are named by
    :func:`channel_names`. ``attributes`` become EXR header attributes.
    """
    path = check_output_path(path)
    if path.suffix.lower() not in LAYERED_FORMATS:
        raise ValueError(f"layers need an .exr file, not {path.suffix!r}")
    planes: list[np.ndarray] = []
    names: list[str] = []
    shape: tuple[int, ...] | None = None
    for aov, image in layers.items():
        img = np.asarray(image, dtype=np.float32)
        if img.ndim == 2:
            img = img[:, :, None]
        if shape is None:
            shape = img.shape[:2]
        if img.ndim != 3 or img.shape[:2] != shape:
            raise ValueError(f"layer {aov!r} has shape {img.shape}, expected {shape}×C")
        planes.append(img)
        names += channel_names(aov, img.shape[2])
    if not planes:
        raise ValueError("no layers to write")
    _write(path, np.concatenate(planes, axis=2), "float", names, attributes)
    return names


def aov_path(output: str | Path, aov: str) -> Path:
    """Where an AOV goes when the output format holds one image: ``NAME.AOV.EXT``."""
    out = Path(output)
    return out.with_name(f"{out.stem}.{aov}{out.suffix}")


def planned_files(output: str | Path, aovs: Iterable[str]) -> list[Path]:
    """The files :func:`save_result` writes for ``output`` and ``aovs``."""
    out = Path(output)
    if out.suffix.lower() in LAYERED_FORMATS:
        return [out]
    return [out, *(aov_path(out, a) for a in aovs)]


def save_result(
    path: str | Path,
    result: RenderResult,
    aovs: Iterable[str] = (),
    tonemap: str = "clip",
    exposure: float = 0.0,
) -> list[Path]:
    """Writes a render: the beauty (``result.radiance``) and the AOVs named in ``aovs``.

    ``.exr``: one file, the beauty as ``R, G, B`` and each AOV as named channels
    (``albedo.R…``, ``N.X…``, ``P.X…``, ``Z``, ``direct.R…``), plus the method, samples
    and render time as header attributes. Other formats: the beauty in ``path`` and each
    AOV in ``NAME.AOV.EXT``; 8-bit formats map AOVs to a visible range
    (:func:`gi.display.aov_display`). Returns the files written.
    """
    from gi import __version__

    path = check_output_path(path)
    display.check_tonemap(tonemap)
    exposure = _checks.exposure_setting(exposure)
    aovs = list(aovs)
    names = result.aov_names()
    for a in aovs:
        if a not in names:
            raise ValueError(f"no AOV {a!r} (available: {', '.join(names)})")
    suffix = path.suffix.lower()
    if suffix in LAYERED_FORMATS:
        layers = {"radiance": result.radiance}
        layers.update({a: result.aov(a) for a in aovs if a != "radiance"})
        s = result.stats
        attributes = {
            "Software": f"gi {__version__}",
            "gi:method": s.method,
            "gi:samples_per_pixel": int(s.samples_per_pixel),
            "gi:render_seconds": float(s.total_seconds),
        }
        save_layers(path, layers, attributes)
        return [path]
    written = [path]
    save_image(path, result.radiance, exposure=exposure, tonemap=tonemap)
    for a in aovs:
        target = aov_path(path, a)
        if suffix in FLOAT_FORMATS:
            save_image(target, result.aov(a))
        else:
            shown = display.aov_display(a, result.aov(a), result.depth, tonemap, exposure)
            img = shown if shown.ndim == 3 else shown[:, :, None]
            _write(check_output_path(target), display.quantize8(img), "uint8")
        written.append(target)
    return written


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


def read_channels(path: str | Path) -> dict[str, np.ndarray]:
    """Reads every channel of an image by name: ``{"R": H×W, "albedo.R": H×W, "Z": …}``."""
    oiio = _oiio()
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise OSError(f"cannot read {path}: {buf.geterror()}")
    pixels = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
    if buf.has_error:  # a truncated or corrupt file
        raise OSError(f"cannot read {path}: {buf.geterror()}")
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return {name: pixels[:, :, i] for i, name in enumerate(buf.spec().channelnames)}
