"""The typed rendering entry point over the native module."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gi import _gi
from gi._gi import Scene
from gi.progress import ProgressBar

ProgressCallback = Callable[[str, float], "bool | None"]


@dataclass(frozen=True)
class RenderStats:
    """Timings (seconds) and counts of one render."""

    method: str
    total_seconds: float
    stages: list[tuple[str, float]] = field(default_factory=list)
    samples_per_pixel: int = 0
    camera_paths: int = 0
    light_paths: int = 0
    triangles: int = 0
    photons_emitted: int = 0
    photons_first_bounce: int = 0
    photons_stored: int = 0
    volume_quads: int = 0


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

    BASE = ("radiance", "albedo", "normal", "position", "depth", "caustics")

    def aov_names(self) -> list[str]:
        """Names :meth:`aov` accepts: the base images, then the method's own (``extra``;
        method ``ispm``: direct, indirect, photons)."""
        return [*self.BASE, *self.extra]

    def aov(self, name: str) -> np.ndarray:
        """An image by name (see :meth:`aov_names`)."""
        if name in self.BASE:
            return getattr(self, name)  # type: ignore[no-any-return]
        if name in self.extra:
            return self.extra[name]
        raise KeyError(f"no image {name!r} (available: {', '.join(self.aov_names())})")

    def __repr__(self) -> str:
        h, w = self.radiance.shape[:2]
        s = self.stats
        return (
            f"<RenderResult {s.method} {w}x{h}, {s.samples_per_pixel} spp,"
            f" {s.total_seconds:.2f} s; aovs: {', '.join(self.aov_names())}>"
        )

    def display(self, tonemap: str = "clip", exposure: float = 0.0) -> np.ndarray:
        """The beauty as 8-bit sRGB (H×W×3 uint8) through a display transform
        (:mod:`gi.display`: "clip", "filmic"/"agx" or "aces")."""
        from gi.display import to_srgb8

        return to_srgb8(self.radiance, exposure, tonemap)

    def _repr_png_(self) -> bytes:
        """The tone-mapped beauty as PNG, for Jupyter."""
        from gi.display import png_bytes

        return png_bytes(self.display())


def render(
    scene: Scene,
    method: str = "path",
    *,
    spp: int = 64,
    size: tuple[int, int] | None = None,
    seed: int = 0,
    max_depth: int = 64,
    light_paths: int | None = None,
    photons: int = 200_000,
    k: int = 100,
    max_radius: float | None = None,
    kernel: str = "cone",
    smoothing: float = 1.0,
    leaf_size: int | None = None,
    kernel_scale: float = 1.0,
    subsample: int = 2,
    footprint_volumes: bool = False,
    boundary_compensation: bool = True,
    volume_shape: str = "auto",
    adapter: str | None = None,
    shadow_map_size: int = 1024,
    progress: bool | ProgressCallback = False,
    denoise: bool = False,
) -> RenderResult:
    """Renders ``scene`` with ``method`` (see :func:`gi.methods`).

    ``size`` is ``(width, height)`` and defaults to the scene camera's. ``spp`` is camera
    samples per pixel; ``light_paths`` the caustic light paths of method ``path`` (default
    one per camera sample). Method ``photon`` (classic photon mapping) emits ``photons``
    photons and estimates radiance from the ``k`` nearest within ``max_radius`` (metres;
    default 5% of the scene's diagonal) with a ``kernel`` of "box", "cone" or "epanechnikov".
    Method ``gather`` traces ``photons`` photons with photon differentials and gathers every
    photon whose footprint (scaled by ``smoothing``, semi-axes at most ``max_radius``)
    contains the shading point, from a linear BVH with ``leaf_size`` footprints per leaf
    (default: the automatic T_auto).
    Method ``ispm`` (image-space photon mapping) rasterizes a bounce map per light with
    ``photons`` first-bounce photons in all, traces later bounces on the CPU and splats one
    photon volume per stored photon, ``kernel_scale`` times the default radius (or sized by
    photon-differential footprints with ``footprint_volumes``), at 1/``subsample``
    resolution with joint bilateral upsampling; ``boundary_compensation`` divides each
    photon's power by the fraction of its kernel that lies on surfaces (probe rays), so
    edges and corners keep their energy. Mirrors and glass seen by the camera are traced
    backwards on the CPU with a photon-map gather (``k``, ``max_radius``, ``kernel``).
    ``volume_shape`` picks the shape drawn per
    photon volume: "icosahedron", "quad" (a screen-aligned bounding rectangle, cheaper for
    small volumes) or "auto" (quads for volumes under 16 pixels in radius, else icosahedra);
    it changes the cost, not the image.
    GPU methods (``direct``, ``ispm``) run on ``adapter`` ("cpu" for lavapipe, "gpu", or part of an
    adapter's name; default: the ``GI_ADAPTER`` environment variable, else a real GPU when
    present, else lavapipe) with ``shadow_map_size``² texels per shadow-map face.
    ``progress`` is a callable ``(stage, fraction) -> bool | None`` (return ``False`` to
    cancel), or ``True`` for progress bars (tqdm; in a terminal or a notebook, nothing in
    logs). The GIL is released while rendering; Ctrl-C cancels with
    :class:`KeyboardInterrupt`.
    ``denoise`` runs Intel Open Image Denoise on the radiance, guided by the albedo and
    normal AOVs (:func:`gi.denoise`); the noisy radiance is kept as the AOV ``noisy``.
    """
    if denoise:
        from gi.denoising import INSTALL_HINT, available

        if not available():
            raise _gi.SettingError(INSTALL_HINT)
    callback: ProgressCallback | None
    if progress is True:
        callback = ProgressBar()
    elif progress is False:
        callback = None
    else:
        callback = progress
    width, height = size if size is not None else (None, None)
    out = _gi.render(
        scene,
        method=method,
        spp=spp,
        width=width,
        height=height,
        seed=seed,
        max_depth=max_depth,
        light_paths=light_paths,
        photons=photons,
        k=k,
        max_radius=max_radius,
        kernel=kernel,
        smoothing=smoothing,
        leaf_size=leaf_size,
        kernel_scale=kernel_scale,
        subsample=subsample,
        footprint_volumes=footprint_volumes,
        boundary_compensation=boundary_compensation,
        volume_shape=volume_shape,
        adapter=adapter,
        shadow_map_size=shadow_map_size,
        progress=callback,
    )
    s = out["stats"]
    stats = RenderStats(
        method=s["method"],
        total_seconds=s["total_seconds"],
        stages=[(str(n), float(t)) for n, t in s["stages"]],
        samples_per_pixel=s["samples_per_pixel"],
        camera_paths=s["camera_paths"],
        light_paths=s["light_paths"],
        triangles=s["triangles"],
        photons_emitted=s["photons_emitted"],
        photons_first_bounce=s["photons_first_bounce"],
        photons_stored=s["photons_stored"],
        volume_quads=s["volume_quads"],
    )
    result = RenderResult(
        radiance=out["radiance"],
        albedo=out["albedo"],
        normal=out["normal"],
        position=out["position"],
        depth=out["depth"],
        caustics=out["caustics"],
        stats=stats,
        extra=dict(out["extra"]),
    )
    if denoise:
        from gi.denoising import denoise as run_denoiser

        result = run_denoiser(result)
    return result
