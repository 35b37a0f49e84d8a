"""A rendered frame: its images, by name, and its statistics (:class:`RenderResult`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gi import _checks, aovs
from gi._gi import RenderStats
from gi.display import png_bytes, to_srgb8


@dataclass(frozen=True)
class RenderResult:
    """A rendered frame. Images are float32 ``(height, width, 3)`` in linear RGB.

    ``radiance`` is in W·sr⁻¹·m⁻² (the pixel's box-filtered mean); ``caustics`` is the
    light-traced part of it; ``albedo``, ``normal``, ``position`` and ``depth`` (view-space
    distance along the camera axis, ``(height, width)``) describe the first surface seen
    through each pixel centre.
    """

    radiance: np.ndarray
    albedo: np.ndarray
    normal: np.ndarray
    position: np.ndarray
    depth: np.ndarray
    caustics: np.ndarray
    stats: RenderStats
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    #: The tone-mapped 8-bit sRGB image (H×W×3 uint8) when the frame was rendered with
    #: ``tonemap=`` (:meth:`gi.Renderer.render`), else empty; ``display_settings`` is its
    #: ``(tonemap, exposure)``.
    display8: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3), np.uint8))
    display_settings: tuple[str, float] | None = None

    BASE = aovs.BASE

    def aov_names(self) -> list[str]:
        """Names :meth:`aov` accepts: the base images that were read back (all of them with
        ``aovs=True``; ``caustics`` for method ``path`` only), then the method's own
        (``extra``; method ``ispm``: direct, specular, indirect, photons)."""
        base = aovs.base_names(self.stats.method)
        return [n for n in base if getattr(self, n).size > 0 or n == "radiance"] + [*self.extra]

    def aov(self, name: str) -> np.ndarray:
        """An image by name (see :meth:`aov_names`); else :class:`gi.SettingError` (also a
        ``KeyError``) saying why it is missing: not read back (``aovs=True``,
        ``extras=True``), not rendered by the method, or unknown."""
        if isinstance(name, str) and name in self.aov_names():
            return getattr(self, name) if name in self.BASE else self.extra[name]  # type: ignore[no-any-return]
        raise _checks.AovError(self._why_missing(name))

    def _why_missing(self, name: object) -> str:
        method = self.stats.method
        available = ", ".join(self.aov_names())
        if not isinstance(name, str):
            return f"AOV names are strings, got {name!r} (available: {available})"
        if name in aovs.base_names(method):
            return (
                f"{name!r} was not read back: render with aovs=True (gi.Renderer.render,"
                f" render_progressive; available: {available})"
            )
        if name in aovs.METHOD_EXTRA.get(method, ()):
            return (
                f"{name!r} was not read back: render with extras=True (gi.Renderer.render,"
                f" render_progressive; available: {available})"
            )
        if name in self.BASE or name in aovs.DENOISE_EXTRA:
            return aovs.why_not(method, name) + f" (this result has: {available})"
        return f"no image {name!r} (available: {available})"

    def __repr__(self) -> str:
        h, w = self.radiance.shape[:2]
        s = self.stats
        samples = f"{s.samples_per_pixel} spp"
        if s.passes > 1:
            samples = f"{s.passes} passes of {s.samples_per_pixel} spp"
        return (
            f"<RenderResult {s.method} {w}x{h}, {samples}, {s.total_seconds:.2f} s;"
            f" aovs: {', '.join(self.aov_names())}>"
        )

    def display(self, tonemap: str = "clip", exposure: float = 0.0) -> np.ndarray:
        """The beauty as 8-bit sRGB (H×W×3 uint8) through a display transform
        (:mod:`gi.display`: "clip", "filmic"/"agx" or "aces"): the frame's own ``display8``
        when it was rendered with these settings, else encoded from ``radiance``."""
        if self.display8.size and self.display_settings == (tonemap, float(exposure)):
            return self.display8
        if self.radiance.size == 0:
            raise _checks.setting_error(
                "radiance",
                "this frame has no radiance (rendered with radiance=None); its display image"
                f" is {self.display_settings!r}",
            )
        return to_srgb8(self.radiance, exposure, tonemap)

    def _repr_png_(self) -> bytes:
        """The tone-mapped beauty as PNG, for Jupyter."""
        return png_bytes(self.display())
