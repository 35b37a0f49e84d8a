"""Environment images: equirectangular (latitude-longitude) HDR files read through
OpenImageIO and handed to the core as float32 (H, W, 3) arrays.

The scene format's ``environment`` section (``docs/scene-format.md``) names the file; this
module reads it. One channel is used as grey, three or more as RGB (an alpha channel is
ignored); two channels, NaN, infinite or negative values are scene errors.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gi.meshes import scene_error

FIELD = "environment.file"


def load_environment_image(path: Path, source: str, field: str = FIELD) -> np.ndarray:
    """Reads ``path`` as float32 (H, W, 3) radiance; raises :class:`gi.SceneError` naming
    ``source`` (the scene file) and ``field`` for a missing, unreadable or invalid image."""
    import OpenImageIO as oiio  # noqa: N813

    if not path.is_file():
        raise scene_error(source, field, f"no such environment image: {path}")
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise scene_error(source, field, f"cannot read {path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    finally:
        inp.close()
    if pixels is None or not isinstance(pixels, np.ndarray):
        raise scene_error(source, field, f"cannot read {path}: {oiio.geterror()}")
    img = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    if spec.nchannels == 1:
        img = np.repeat(img, 3, axis=2)
    elif spec.nchannels == 2:
        raise scene_error(source, field, f"{path} has 2 channels; need 1 (grey) or RGB")
    else:
        img = img[:, :, :3]
    return check_environment_array(img, source, field)


def check_environment_array(img: Any, source: str, field: str = FIELD) -> np.ndarray:
    """``img`` as a C-contiguous float32 (H, W, 3) array of finite, non-negative values."""
    arr = np.asarray(img)
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise scene_error(source, field, f"environment image must be (H, W, 3), got {arr.shape}")
    arr = np.ascontiguousarray(arr, dtype=np.float32)
    bad = ~np.isfinite(arr) | (arr < 0)
    if bad.any():
        row, col, _ = np.argwhere(bad)[0]
        raise scene_error(
            source,
            field,
            f"texel (row {row}, column {col}) is not finite and non-negative: {arr[row, col]}",
        )
    return arr


def load_environment(desc: Any, base_dir: Path, source: str) -> dict[str, np.ndarray]:
    """The images a scene description's ``environment`` section names, keyed by ``file``
    (what ``Scene.from_json`` takes as ``images``); empty without a file."""
    env = desc.get("environment") if isinstance(desc, dict) else None
    name = env.get("file") if isinstance(env, dict) else None
    if not isinstance(name, str) or "radiance" in env:
        return {}  # the core reports a missing, mistyped or ambiguous section
    return {name: load_environment_image(base_dir / name, source)}
