"""Denoising with Intel Open Image Denoise (the ``pyoidn`` binding from PyPI).

OIDN's ``RT`` filter takes the HDR beauty with gi's first-hit ``albedo`` and ``normal``
AOVs as guides. Those are taken at each pixel's centre, so they are noise-free (not
antialiased); they are passed as clean auxiliaries (``cleanAux``), which gave a lower FLIP
than letting OIDN prefilter them in 10 of 11 comparisons (path, photon, gather, ispm; the
exception, ispm in docs/bench/denoise.md, by 0.3 %).
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING

import numpy as np

from gi._gi import SettingError

if TYPE_CHECKING:
    from gi.render import RenderResult

INSTALL_HINT = "denoising needs Intel Open Image Denoise: pip install 'gi[denoise]' (pyoidn)"


def available() -> bool:
    """Whether the OIDN binding can be imported."""
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        return False
    return True


def denoise_image(
    radiance: np.ndarray,
    albedo: np.ndarray | None = None,
    normal: np.ndarray | None = None,
    clean_aux: bool = True,
) -> np.ndarray:
    """Denoises an HDR H×W×3 radiance image, guided by albedo and normal (both optional)."""
    try:
        import pyoidn
    except ImportError as e:
        raise SettingError(INSTALL_HINT) from e

    def prep(img: np.ndarray, lo: float, hi: float) -> np.ndarray:
        x = np.nan_to_num(np.asarray(img, dtype=np.float32), nan=0.0, posinf=hi, neginf=lo)
        return np.ascontiguousarray(np.clip(x, lo, hi))

    color = prep(radiance, 0.0, np.finfo(np.float32).max)
    if color.ndim != 3 or color.shape[2] != 3:
        raise ValueError(f"radiance must be H×W×3, got shape {color.shape}")
    alb = prep(albedo, 0.0, 1.0) if albedo is not None else None
    nrm = prep(normal, -1.0, 1.0) if normal is not None else None
    if nrm is not None and alb is None:
        raise ValueError("OIDN takes a normal image only together with an albedo image")
    try:
        out = pyoidn.denoise(color, alb, nrm, hdr=True, clean_aux=clean_aux, quality="high")
    except (RuntimeError, ValueError, TypeError) as e:
        raise SettingError(f"denoising failed: {e}") from e
    return np.asarray(out, dtype=np.float32)


def denoise(result: RenderResult) -> RenderResult:
    """A copy of ``result`` whose ``radiance`` is denoised; the input radiance is kept as
    the AOV ``noisy`` and the time taken is the stage ``denoise`` in ``stats``."""
    t = time.perf_counter()
    clean = denoise_image(result.radiance, result.albedo, result.normal)
    seconds = time.perf_counter() - t
    stats = dataclasses.replace(
        result.stats,
        stages=[*result.stats.stages, ("denoise", seconds)],
        total_seconds=result.stats.total_seconds + seconds,
    )
    extra = {**result.extra, "noisy": result.radiance}
    return dataclasses.replace(result, radiance=clean, extra=extra, stats=stats)
