"""Image output through OpenImageIO.

``.exr`` keeps float radiance and holds every requested AOV as named layers in one file;
``.hdr``/``.pfm``/``.tif`` keep float values, one image per file; ``.png``/``.jpg`` are
8-bit sRGB through a display transform (see :mod:`gi.display`). Every argument is checked
before anything is written; the files of one call are written to temporary names beside
their targets and renamed into place only once all of them are written, so a failed write
leaves no partial file and no partial set of files.

Errors are typed: :class:`gi.SettingError` (also a ``ValueError``) for a bad argument (an
unknown format, tone mapper or AOV, an image shape a format cannot hold), naming it and
what it allows; :class:`gi.OutputError` (also an ``OSError``) for a file that cannot be
written.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gi import _checks, display
from gi._checks import OutputError, named_error
from gi._gi import __version__
from gi.result import RenderResult

#: Suffixes holding several AOVs as layers of one file.
LAYERED_FORMATS = {".exr"}
#: Suffixes written as linear float images.
FLOAT_FORMATS = {".exr", ".hdr", ".pfm", ".tif", ".tiff"}
#: Suffixes written as 8-bit sRGB through a display transform.
SRGB_FORMATS = {".png", ".jpg", ".jpeg"}
#: Channel counts a format holds, where it does not hold any (OpenImageIO's writers). An
#: image of one channel is written as grey RGB where one channel is not held (``.hdr``);
#: other counts a format does not hold are refused before anything is written.
FORMAT_CHANNELS = {
    ".hdr": (3,),
    ".pfm": (1, 3),
    ".png": (1, 2, 3, 4),
    ".jpg": (1, 3),
    ".jpeg": (1, 3),
}


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


def _as_path(path: Any, setting: str = "path") -> Path:
    if isinstance(path, (str, os.PathLike)):
        try:
            out = Path(path)
        except TypeError:
            pass
        else:
            if "\0" not in str(out):
                return out
    raise named_error(setting, f"invalid setting `{setting}`: expected a file path, got {path!r}")


def check_format(path: str | Path) -> Path:
    """``path`` if its extension is an image format gi writes, else :class:`gi.SettingError`
    (also a ``ValueError``) naming the formats."""
    path = _as_path(path)
    if path.suffix.lower() not in FLOAT_FORMATS | SRGB_FORMATS:
        known = ", ".join(sorted(FLOAT_FORMATS | SRGB_FORMATS))
        raise named_error(
            "path", f"unsupported image format {path.suffix!r} for {path} (use {known})"
        )
    return path


def check_output_path(path: str | Path) -> Path:
    """Checks that ``path`` has a supported extension and can be written, without writing.

    Raises :class:`gi.SettingError` (also a ``ValueError``) for an unknown format and
    :class:`gi.OutputError` (also an ``OSError``) for a path that is a directory or lies in
    a directory that cannot be created or written.
    """
    return check_writable(check_format(path))


def check_writable(path: str | Path) -> Path:
    """Raises :class:`gi.OutputError` if ``path`` is a directory or lies in a directory that
    cannot be created or written. Whether a directory can be written is tried, not read from
    its permission bits (which a root user passes even on ``/proc``): a probe file is made
    in the nearest existing directory and removed at once."""
    path = _as_path(path)
    try:
        if path.is_dir():
            raise OutputError(path, "it is a directory")
        parent = path.absolute().parent
        while not parent.exists():
            parent = parent.parent
    except (OSError, ValueError) as e:  # a name too long, a NUL byte
        if isinstance(e, OutputError):
            raise
        raise OutputError(path, str(e)) from e
    if not parent.is_dir():
        raise OutputError(path, f"{parent} is not a directory")
    try:
        fd, probe = tempfile.mkstemp(prefix=".gi-probe-", dir=parent)
    except OSError as e:
        raise OutputError(path, _why_not_writable(parent, e)) from e
    os.close(fd)
    os.unlink(probe)
    return path


def _why_not_writable(directory: Path, e: OSError) -> str:
    """Why no file can be made in the existing ``directory``, in words that match the
    error: a file system that makes no new files (``/proc``) answers "no such
    file" for a directory that exists."""
    if e.errno in (errno.EACCES, errno.EPERM):
        return f"{directory} is not writable (permission denied)"
    if e.errno == errno.EROFS:
        return f"{directory} is on a read-only file system"
    if e.errno == errno.ENOENT:
        return f"{directory} is on a file system that makes no new files (such as /proc)"
    return f"cannot create a file in {directory} ({e.strerror or e})"


@dataclass
class _Planned:
    """One file of a write: H×W×C ``data`` in OpenImageIO pixel format ``fmt``."""

    path: Path
    data: np.ndarray
    fmt: str
    names: list[str] | None = None
    attributes: Mapping[str, str | int | float] = field(default_factory=dict)


def _fit_channels(path: Path, img: np.ndarray, what: str) -> np.ndarray:
    """``img`` (H×W×C) with channels ``path``'s format holds: one channel becomes grey RGB
    where the format holds no single channel; other counts it does not hold are refused."""
    held = FORMAT_CHANNELS.get(path.suffix.lower())
    c = img.shape[2]
    if held is None or c in held:
        return img
    if c == 1 and 3 in held:
        return np.repeat(img, 3, axis=2)
    counts = " or ".join(map(str, held))
    raise named_error(
        "image",
        f"{what} for {path}: a {path.suffix} file holds {counts} channels, the image has {c}"
        " (use .exr or .tif for any number of channels)",
    )


def _write_tmp(p: _Planned) -> Path:
    """Writes ``p`` to a hidden temporary file beside its target and reads it back."""
    oiio = _oiio()
    h, w, c = p.data.shape
    try:
        p.path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(p.path, f"cannot make its directory ({e.strerror or e})") from e
    out = oiio.ImageOutput.create(str(p.path))
    if out is None:
        raise OutputError(p.path, oiio.geterror() or "no writer for this format")
    spec = oiio.ImageSpec(w, h, c, p.fmt)
    if p.names is not None:
        spec.channelnames = tuple(p.names)
    for key, value in p.attributes.items():
        spec.attribute(key, value)
    tmp = p.path.with_name(f".{p.path.stem}.{os.getpid()}.tmp{p.path.suffix}")
    try:
        try:
            ok = out.open(str(tmp), spec) and out.write_image(np.ascontiguousarray(p.data))
            if not ok:
                raise OutputError(p.path, out.geterror() or "the writer failed")
        finally:
            closed = out.close()
        if not closed:
            raise OutputError(p.path, out.geterror() or "closing failed")
        # Read back in full: libpng reports no error for a short write (disk full, a
        # file-size limit), which would otherwise replace a good file with a truncated one.
        try:
            read_image(tmp)
        except OSError as e:
            raise OutputError(p.path, f"the written file does not read back ({e})") from e
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return tmp


def _write_all(planned: list[_Planned]) -> list[Path]:
    """Writes every planned file, or none: each goes to a temporary file first, and they are
    renamed into place only when all of them were written and read back."""
    written: list[tuple[Path, Path]] = []
    try:
        for p in planned:
            written.append((_write_tmp(p), p.path))
        for tmp, target in written:
            try:
                os.replace(tmp, target)
            except OSError as e:
                raise OutputError(target, e.strerror or str(e)) from e
    except BaseException:
        for tmp, _ in written:
            tmp.unlink(missing_ok=True)
        raise
    return [p.path for p in planned]


def _image_array(image: Any, what: str) -> np.ndarray:
    """``image`` as float32 H×W×C (H×W: one channel), else :class:`gi.SettingError`."""
    try:
        arr = np.asarray(image)
    except (TypeError, ValueError) as e:  # ragged nested lists
        raise named_error("image", f"{what}: expected a float array (H×W or H×W×C): {e}") from e
    if arr.dtype.kind not in "biuf":
        raise named_error(
            "image", f"{what}: expected real numbers (H×W or H×W×C), got dtype {arr.dtype}"
        )
    with np.errstate(over="ignore"):  # float64 beyond float32's range: infinity, as stored
        img = arr.astype(np.float32)
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3 or 0 in img.shape:
        raise named_error(
            "image", f"{what}: expected a non-empty H×W or H×W×C array, got shape {img.shape}"
        )
    return img


def save_image(
    path: str | Path, image: np.ndarray, exposure: float = 0.0, tonemap: str = "clip"
) -> None:
    """Writes ``image`` (H×W×C or H×W float) to ``path``.

    ``.exr`` (and ``.hdr``/``.pfm``/``.tif``) store linear float values as they are;
    ``.png``/``.jpg`` store 8-bit sRGB through ``tonemap`` (see :mod:`gi.display`) after
    ``exposure`` stops. One channel (a depth image) is written as grey RGB to formats that
    hold no single channel (``.hdr``); a channel count a format cannot hold is refused.
    """
    path = check_format(path)
    display.check_tonemap(tonemap)
    exposure = _checks.exposure_setting(exposure)
    img = _fit_channels(path, _image_array(image, "image"), "image")
    check_writable(path)
    _write_all([_plan_image(path, img, exposure, tonemap)])


def _plan_image(path: Path, img: np.ndarray, exposure: float, tonemap: str) -> _Planned:
    if path.suffix.lower() in FLOAT_FORMATS:
        return _Planned(path, img, "float")
    return _Planned(path, display.to_srgb8(img, exposure, tonemap), "uint8")


def save_layers(
    path: str | Path,
    layers: Mapping[str, np.ndarray],
    attributes: Mapping[str, str | int | float] | None = None,
) -> list[str]:
    """Writes named float images into one multichannel EXR; returns its channel names.

    ``layers`` maps AOV names to H×W×3 or H×W arrays of one size; channels are named by
    :func:`channel_names`. ``attributes`` become EXR header attributes.
    """
    path = check_format(path)
    planned = _plan_layers(path, layers, attributes or {})
    check_writable(path)
    _write_all([planned])
    return planned.names or []


def _plan_layers(
    path: Path, layers: Mapping[str, np.ndarray], attributes: Mapping[str, str | int | float]
) -> _Planned:
    if path.suffix.lower() not in LAYERED_FORMATS:
        raise named_error("path", f"layers need an .exr file, not {path.suffix!r} ({path})")
    planes: list[np.ndarray] = []
    names: list[str] = []
    shape: tuple[int, ...] | None = None
    for aov, image in layers.items():
        img = _image_array(image, f"layer {aov!r}")
        if shape is None:
            shape = img.shape[:2]
        if img.shape[:2] != shape:
            raise named_error(
                "layers", f"layer {aov!r} has shape {img.shape}, expected {shape}×C like the first"
            )
        planes.append(img)
        names += channel_names(aov, img.shape[2])
    if not planes:
        raise named_error("layers", "no layers to write")
    return _Planned(path, np.concatenate(planes, axis=2), "float", names, attributes)


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
    per pixel (of all passes, for a progressive result), passes and render time as header
    attributes. Other formats: the beauty in ``path`` and each AOV in ``NAME.AOV.EXT``;
    8-bit formats map AOVs to a visible range (:func:`gi.display.aov_display`), ``.hdr``
    writes the one-channel depth as grey RGB. Everything is checked before anything is
    written, and either every file is written or none. Returns the files written.
    """
    planned = plan_result(path, result, aovs, tonemap, exposure)
    for p in {p.path.absolute().parent: p for p in planned}.values():
        check_writable(p.path)
    return _write_all(planned)


def plan_result(
    path: str | Path,
    result: RenderResult,
    aovs: Iterable[str] = (),
    tonemap: str = "clip",
    exposure: float = 0.0,
) -> list[_Planned]:
    """The files :func:`save_result` writes, converted and checked, without writing."""
    path = check_format(path)
    if not isinstance(result, RenderResult):
        raise named_error(
            "result", f"invalid setting `result`: expected a gi.RenderResult, got {result!r}"
        )
    display.check_tonemap(tonemap)
    exposure = _checks.exposure_setting(exposure)
    if isinstance(aovs, str):
        aovs = [aovs]
    try:
        aovs = list(dict.fromkeys(aovs))
    except TypeError:
        raise named_error(
            "aovs", f"invalid setting `aovs`: expected AOV names, got {aovs!r}"
        ) from None
    images = {a: result.aov(a) for a in aovs if a != "radiance"}
    suffix = path.suffix.lower()
    if suffix in LAYERED_FORMATS:
        s = result.stats
        attributes = {
            "Software": f"gi {__version__}",
            "gi:method": s.method,
            "gi:samples_per_pixel": int(s.samples_per_pixel) * max(int(s.passes), 1),
            "gi:passes": int(s.passes),
            "gi:render_seconds": float(s.total_seconds),
        }
        return [_plan_layers(path, {"radiance": result.radiance, **images}, attributes)]
    beauty = _fit_channels(path, _image_array(result.radiance, "radiance"), "radiance")
    planned = [_plan_image(path, beauty, exposure, tonemap)]
    for a, image in images.items():
        target = aov_path(path, a)
        img = _fit_channels(target, _image_array(image, a), a)
        if suffix in FLOAT_FORMATS:
            planned.append(_Planned(target, img, "float"))
        else:
            shown = display.aov_display(a, image, result.depth, tonemap, exposure)
            shown = shown if shown.ndim == 3 else shown[:, :, None]
            planned.append(_Planned(target, display.quantize8(shown), "uint8"))
    return planned


def read_image(path: str | Path, layer: str | None = None) -> np.ndarray:
    """Reads an image as float32 H×W×C (8-bit formats scaled to [0, 1], not linearised).

    A layered EXR (the AOVs gi writes as layers of one file) reads as its beauty, the
    channels without a layer name (``R``, ``G``, ``B``), so that the image can be saved
    to any format again; ``layer="albedo"`` reads that layer's channels instead
    (``albedo.R`` …, in the file's order), and :func:`read_channels` every channel by
    name. An unknown ``layer`` is a :class:`gi.SettingError` naming the layers the file
    has."""
    oiio = _oiio()
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise OSError(f"cannot read {path}: {oiio.geterror() or 'unknown format'}")
    try:
        names = list(inp.spec().channelnames)
        pixels = inp.read_image(oiio.FLOAT)
        error = inp.geterror()
    finally:
        inp.close()
    # A truncated or corrupt file reads as `None` or with an error, never as zeros.
    if pixels is None or error:
        raise OSError(f"cannot read {path}: {error or 'truncated or corrupt'}")
    arr = np.asarray(pixels, dtype=np.float32)
    arr = arr if arr.ndim == 3 else arr.reshape(arr.shape[0], arr.shape[1], -1)
    return _layer_channels(path, arr, names, layer)


def _layer_channels(
    path: str | Path, arr: np.ndarray, names: list[str], layer: str | None
) -> np.ndarray:
    """The channels of ``layer`` (``None``: those without a layer name) of ``arr``."""
    layers = {n.rpartition(".")[0] for n in names}
    if layer is None and (layers == {""} or "" not in layers):
        return arr  # not layered (or nothing but layers): every channel
    want = "" if layer is None else layer
    if not isinstance(want, str) or want not in layers:
        shown = ", ".join(sorted(repr(n) for n in layers if n)) or "none"
        raise named_error("layer", f"{path} has no layer {layer!r} (its layers: {shown})")
    keep = [i for i, n in enumerate(names) if n.rpartition(".")[0] == want]
    return arr[:, :, keep]


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
