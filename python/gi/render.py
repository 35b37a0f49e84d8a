"""The typed rendering entry point over the native module."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gi import _checks, _gi
from gi._gi import Scene

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


class ProgressBar:
    """A one-line text progress bar on stderr, for the CLI and interactive use."""

    def __init__(self, stream=None, width: int = 30) -> None:  # type: ignore[no-untyped-def]
        self.stream = stream or sys.stderr
        self.width = width
        self.start = time.monotonic()

    def __call__(self, stage: str, fraction: float) -> bool:
        filled = int(self.width * min(max(fraction, 0.0), 1.0))
        bar = "#" * filled + "-" * (self.width - filled)
        elapsed = time.monotonic() - self.start
        end = "\n" if fraction >= 1.0 else ""
        self.stream.write(f"\r{stage:>8} [{bar}] {fraction * 100:5.1f}% {elapsed:6.1f}s{end}")
        self.stream.flush()
        return True


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
    cancel), or ``True`` for a text bar on stderr. The GIL is released while rendering;
    Ctrl-C cancels with :class:`KeyboardInterrupt`.
    """
    callback: ProgressCallback | None
    if progress is True:
        callback = ProgressBar()
    elif progress is False or progress is None:
        callback = None
    elif callable(progress):
        callback = progress
    else:
        raise _checks.setting_error("progress", f"must be a bool or a callable, got {progress!r}")
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a gi.Scene (see gi.load_scene), got {type(scene).__name__}")
    width, height = _checks.size_setting(size)
    out = _gi.render(
        scene,
        method=_checks.str_setting("method", method),
        spp=_checks.int_setting("spp", spp),
        width=width,
        height=height,
        seed=_checks.int_setting("seed", seed, _checks.U64_MAX),
        max_depth=_checks.int_setting("max_depth", max_depth),
        light_paths=_checks.optional_int("light_paths", light_paths, _checks.U64_MAX),
        photons=_checks.int_setting("photons", photons, _checks.U64_MAX),
        k=_checks.int_setting("k", k),
        max_radius=_checks.optional_float("max_radius", max_radius),
        kernel=_checks.str_setting("kernel", kernel),
        smoothing=_checks.float_setting("smoothing", smoothing),
        leaf_size=_checks.optional_int("leaf_size", leaf_size),
        kernel_scale=_checks.float_setting("kernel_scale", kernel_scale),
        subsample=_checks.int_setting("subsample", subsample),
        footprint_volumes=_checks.bool_setting("footprint_volumes", footprint_volumes),
        boundary_compensation=_checks.bool_setting("boundary_compensation", boundary_compensation),
        volume_shape=_checks.str_setting("volume_shape", volume_shape),
        adapter=_checks.str_setting("adapter", adapter, optional=True),
        shadow_map_size=_checks.int_setting("shadow_map_size", shadow_map_size),
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
    return RenderResult(
        radiance=out["radiance"],
        albedo=out["albedo"],
        normal=out["normal"],
        position=out["position"],
        depth=out["depth"],
        caustics=out["caustics"],
        stats=stats,
        extra=dict(out["extra"]),
    )
