"""Denoising with Intel Open Image Denoise (the ``pyoidn`` binding from PyPI).

Method ``ispm`` first gets a photon-scale filter of its indirect light (`filter_indirect`):
its error is not pixel noise but photon-volume blotches a few pixels wide, which OIDN keeps
as signal (docs/bench/denoise.md, scripts/probe/ispm_error_breakdown.py).

OIDN's ``RT`` filter takes the HDR beauty with gi's first-hit ``albedo`` and ``normal``
AOVs as guides. Those are taken at each pixel's centre, so they are noise-free (not
antialiased); they are passed as clean auxiliaries (``cleanAux``), which gave a lower FLIP
than letting OIDN prefilter them in 10 of 11 comparisons (path, photon, gather, ispm; the
exception, ispm in docs/bench/denoise.md, by 0.3 %).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from gi._checks import setting_error
from gi._gi import SettingError
from gi.result import RenderResult

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


#: B3-spline taps of the à-trous wavelet filter.
_B3 = (1 / 16, 1 / 4, 3 / 8, 1 / 4, 1 / 16)


def filter_indirect(
    indirect: np.ndarray,
    albedo: np.ndarray,
    normal: np.ndarray,
    depth: np.ndarray,
    sigma_px: float | None = None,
) -> np.ndarray:
    """Edge-avoiding à-trous filter (Dammertz et al. 2010) of an indirect-light image at the
    scale of ISPM's photon volumes: the light is divided by the albedo (so texture and
    colour edges stay), smoothed by B3-spline passes of growing spacing until the footprint
    reaches about ``2·sigma_px`` (default: 1/32 of the image width, the photon volumes'
    size at the default settings), weighted down across normal (σ 0.1) and depth (σ 5 % of
    the depth) discontinuities, and multiplied back. Pixels that saw nothing stay 0."""
    h, w = indirect.shape[:2]
    if sigma_px is None:
        sigma_px = w / 32.0
    alb = np.maximum(np.asarray(albedo, np.float32), 1e-3)
    seen = np.asarray(depth, np.float32) > 0
    img = np.where(seen[..., None], np.asarray(indirect, np.float32) / alb, 0.0)
    nrm = np.asarray(normal, np.float32)
    z = np.asarray(depth, np.float32)
    passes = max(1, int(np.ceil(np.log2(sigma_px + 1.0))))
    for i in range(passes):
        step = 2**i
        r = 2 * step
        pad = ((r, r), (r, r))
        pi = np.pad(img, (*pad, (0, 0)), mode="edge")
        pn = np.pad(nrm, (*pad, (0, 0)), mode="edge")
        pz = np.pad(z, pad, mode="edge")
        ps = np.pad(seen, pad, mode="constant")
        acc = np.zeros_like(img)
        wsum = np.zeros((h, w, 1), np.float32)
        for ky, hy in enumerate(_B3):
            for kx, hx in enumerate(_B3):
                dy, dx = (ky - 2) * step, (kx - 2) * step
                sl = (slice(r + dy, r + dy + h), slice(r + dx, r + dx + w))
                dn = ((pn[sl] - nrm) ** 2).sum(-1)
                dz = (pz[sl] - z) ** 2 / np.maximum((0.05 * z) ** 2, 1e-12)
                wt = hx * hy * np.exp(-dn / (2 * 0.1**2) - dz / 2) * ps[sl]
                acc += wt[..., None] * pi[sl]
                wsum += wt[..., None]
        img = np.where(wsum > 0, acc / np.maximum(wsum, 1e-30), img)
    return np.where(seen[..., None], img * alb, 0.0).astype(np.float32)


def denoise(result: RenderResult) -> RenderResult:
    """A copy of ``result`` whose ``radiance`` is denoised; the input radiance is kept as
    the AOV ``noisy`` and the time taken is the stage ``denoise`` in ``stats``. For ``ispm``
    (results with the ``direct``, ``specular`` and ``indirect`` AOVs) the indirect light is
    first filtered at the photon scale (`filter_indirect`) and recomposed."""
    if not isinstance(result, RenderResult):
        raise setting_error("result", f"expected a gi.RenderResult, got {result!r}")
    for name in ("albedo", "normal"):
        if getattr(result, name).size == 0:
            raise setting_error(
                "aovs",
                "denoising is guided by the albedo and normal AOVs, which this result lacks:"
                f" render with aovs=True ({result!r})",
            )
    t = time.perf_counter()
    radiance = result.radiance
    parts = ("direct", "specular", "indirect")
    if all(p in result.extra for p in parts) and result.depth.size:
        filtered = filter_indirect(
            result.extra["indirect"], result.albedo, result.normal, result.depth
        )
        radiance = result.extra["direct"] + result.extra["specular"] + filtered
    clean = denoise_image(radiance, result.albedo, result.normal)
    seconds = time.perf_counter() - t
    stats = result.stats.with_stage("denoise", seconds)
    extra = {**result.extra, "noisy": result.radiance}
    return dataclasses.replace(result, radiance=clean, extra=extra, stats=stats)
