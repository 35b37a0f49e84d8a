"""The typed rendering entry point over the native module."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gi import _checks, _gi
from gi._gi import Scene, SettingError
from gi.progress import ProgressBar

ProgressCallback = Callable[[str, float], "bool | None"]


@dataclass(frozen=True)
class RenderStats:
    """Timings (seconds) and counts of one render."""

    method: str
    total_seconds: float
    stages: list[tuple[str, float]] = field(default_factory=list)
    samples_per_pixel: int = 0
    #: Camera paths traced: method ``path``'s; method ``ispm``'s through mirrors and glass,
    #: 0 in a frame whose lights alone changed (it reuses where they landed).
    camera_paths: int = 0
    light_paths: int = 0
    triangles: int = 0
    photons_emitted: int = 0
    photons_first_bounce: int = 0
    photons_stored: int = 0
    #: Method ``ispm``: stored photons of caustic paths (light → mirrors/glass → surface).
    caustic_photons: int = 0
    volume_quads: int = 0
    passes: int = 1
    #: Method ``ispm``: the indirect estimator that ran ("volumes", "tiled", ...), why it was
    #: chosen, and its GPU memory beyond the image targets (bytes by part).
    estimator: str = ""
    estimator_reason: str = ""
    estimator_memory: list[tuple[str, int]] = field(default_factory=list)
    #: Method ``ispm``: where the photons' first hits were found ("raster" bounce maps or
    #: "traced" in the CPU BVH) and why.
    first_bounce: str = ""
    first_bounce_reason: str = ""
    #: Estimators "tiled" and "cluster": photon-list entries written, and of them the
    #: cluster hierarchy's trivial accepts (one photon for a whole node of view samples).
    list_entries: int = 0
    trivial_accepts: int = 0
    #: Method ``bidir``: virtual point lights and ray bundles of the frame, the fragments the
    #: bundles stored, and those dropped because ``bundle_memory_mb`` was full.
    vpls: int = 0
    bundles: int = 0
    bundle_fragments: int = 0
    bundle_overflow: int = 0


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


def _settings(**kw: object) -> dict[str, object]:
    """Keyword settings for the native module, with ``size`` split into width and height."""
    size = kw.pop("size", None)
    if size is not None:
        try:
            kw["width"], kw["height"] = size  # type: ignore[misc]
        except (TypeError, ValueError):
            raise _checks.setting_error("size", f"expected (width, height), got {size!r}") from None
    return kw


def _progress(progress: bool | ProgressCallback) -> ProgressCallback | None:
    if progress is True:
        return ProgressBar()
    if progress is False or progress is None:
        return None
    if not callable(progress):
        raise _checks.setting_error("progress", f"must be a bool or a callable, got {progress!r}")
    return progress


def _result(out: dict[str, Any]) -> RenderResult:
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
        caustic_photons=s["caustic_photons"],
        volume_quads=s["volume_quads"],
        passes=s["passes"],
        estimator=s["estimator"],
        estimator_reason=s["estimator_reason"],
        estimator_memory=[(str(n), int(b)) for n, b in s["estimator_memory"]],
        first_bounce=s["first_bounce"],
        first_bounce_reason=s["first_bounce_reason"],
        list_entries=s["list_entries"],
        trivial_accepts=s["trivial_accepts"],
        vpls=s["vpls"],
        bundles=s["bundles"],
        bundle_fragments=s["bundle_fragments"],
        bundle_overflow=s["bundle_overflow"],
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


class Renderer:
    """A persistent renderer: made once from a scene, a method and its settings (the
    keywords of :func:`render`, plus ``temporal_frames`` for method ``ispm``), then one
    :meth:`render` per frame with :meth:`update` calls between frames. GPU resources, the
    BVH and the photon ring live from one frame to the next; a frame uploads only what
    changed and reads back only the images asked for.

    >>> r = gi.Renderer(gi.load_scene("cornell"), "ispm", size=(320, 240), photons=50_000)
    >>> r.update(lights={0: {"position": [0.2, 1.9, 0.0]}})
    >>> frame = r.render()                    # radiance only; aovs=True for the rest

    With ``progressive=True`` (methods ``ispm``, ``gather``, ``path``, ``direct``) each
    :meth:`render` is one pass of probabilistic progressive photon mapping (Knaus & Zwicker
    2011): an independent estimate with new photons, pixel jitter and light samples, whose
    photon kernels shrink as r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1) (``progressive_alpha``, α = 0.7),
    and the returned radiance is the mean of the passes since the last :meth:`update` or
    :meth:`resize` (which start over). It converges to the reference as passes are added;
    :meth:`render_progressive` runs passes for a time or a count. The AOVs and ``extra``
    images are those of the last pass.
    """

    def __init__(self, scene: Scene, method: str = "ispm", **settings: Any) -> None:
        if not isinstance(method, str):
            raise _checks.setting_error("method", f"must be a string, got {method!r}")
        self._native = _gi.Renderer(scene, method, _settings(**settings))
        self._scene = scene

    @property
    def method(self) -> str:
        return self._native.method

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)`` of the frames."""
        return self._native.size

    @property
    def frame_index(self) -> int:
        """Frames rendered so far."""
        return self._native.frame_index

    @property
    def passes(self) -> int:
        """Progressive mode: passes averaged into the current image (0 after a change)."""
        return self._native.passes

    @property
    def object_names(self) -> list[str | None]:
        """Names of the scene's objects (``None`` where unnamed), in scene order."""
        return self._native.object_names

    def describe(self, target: str, key: int | str | None = None) -> dict[str, Any]:
        """The current ``"camera"``, ``"light"`` (key: index) or ``"material"`` (key: name)
        in the scene format."""
        return json.loads(self._native.describe(target, key))  # type: ignore[no-any-return]

    def update(
        self,
        *,
        camera: dict[str, Any] | None = None,
        lights: dict[int, dict[str, Any]] | None = None,
        objects: dict[int | str, dict[str, Any]] | None = None,
        materials: dict[str, dict[str, Any]] | None = None,
    ) -> None:
        """Changes the scene before the next frame, in the scene format's terms.

        ``camera`` and each ``lights[i]`` / ``materials[name]`` give the fields that change
        (``{"position": [0, 1, 3]}``); ``objects[name or index]`` gives the object's whole
        transform (``translate``/``rotate``/``scale`` as in the scene file, or
        ``{"matrix": 4×4 rows}``). Invalid values raise :class:`gi.SceneError` and change
        nothing.
        """
        if camera is not None:
            self._native.update("camera", None, json.dumps(camera))
        for i, light in (lights or {}).items():
            self._native.update("light", i, json.dumps(light))
        for key, transform in (objects or {}).items():
            self._native.update("object", key, json.dumps(_jsonable(transform)))
        for name, material in (materials or {}).items():
            self._native.update("material", name, json.dumps(material))

    def resize(self, width: int, height: int) -> None:
        """Changes the image size (render targets are rebuilt at the next frame)."""
        self._native.resize(width, height)

    def render(
        self,
        *,
        aovs: bool = False,
        extras: bool = False,
        seed: int | None = None,
        progress: bool | ProgressCallback = False,
    ) -> RenderResult:
        """Renders one frame. Only the radiance is read back unless ``aovs`` (albedo,
        normal, position, depth) or ``extras`` (the method's own images) are asked for;
        images not asked for are empty arrays. ``seed`` overrides the frame's random seed."""
        out = self._native.render(aovs=aovs, extras=extras, seed=seed, progress=_progress(progress))
        return _result(out)

    def render_progressive(
        self,
        *,
        passes: int | None = None,
        seconds: float | None = None,
        aovs: bool = False,
        extras: bool = False,
        progress: bool | ProgressCallback = False,
        on_pass: Callable[[RenderResult], bool | None] | None = None,
    ) -> RenderResult:
        """Adds progressive passes (the renderer needs ``progressive=True``) until
        ``passes`` in all are averaged or ``seconds`` have passed (at least one pass; both
        may be given, the first reached stops), and returns the mean image.

        ``progress=True`` draws a bar over the passes (or the time); a callable gets
        ``("passes", fraction done)`` and stops the run by returning ``False``. ``on_pass``
        gets each pass's running mean and stops the run by returning ``False``. Ctrl-C
        (:class:`KeyboardInterrupt`) or a cancel during a pass stops at once and returns the
        mean of the passes done so far (``stats.passes`` says how many); with none done it
        raises.
        """
        if not self._native.progressive:
            raise _checks.setting_error(
                "progressive", "render_progressive needs gi.Renderer(..., progressive=True)"
            )
        if passes is None and seconds is None:
            raise _checks.setting_error("passes", "give passes=N or seconds=S")
        if passes is not None and (not isinstance(passes, int) or passes < 1):
            raise _checks.setting_error("passes", f"must be a positive integer, got {passes!r}")
        if seconds is not None and not (
            isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds > 0
        ):
            raise _checks.setting_error("seconds", f"must be a positive number, got {seconds!r}")
        report = _progress(progress)
        start = time.monotonic()
        result: RenderResult | None = None
        # Read between passes only: the native renderer is busy during one.
        done = self.passes

        def done_fraction() -> float:
            f = 0.0
            if passes is not None:
                f = max(f, done / passes)
            if seconds is not None:
                f = max(f, (time.monotonic() - start) / seconds)
            return min(f, 1.0)

        def within_pass(stage: str, fraction: float) -> bool:
            # The bar follows the run, not the stages of a pass; a False from the callback
            # cancels the pass at once (the passes done so far are returned).
            if report is None:
                return True
            return report("passes", min(done_fraction(), 0.999)) is not False

        try:
            while result is None or done_fraction() < 1.0:
                out = self._native.render(aovs=aovs, extras=extras, seed=None, progress=within_pass)
                result = _result(out)
                done = result.stats.passes
                stop = report is not None and report("passes", done_fraction()) is False
                if (on_pass is not None and on_pass(result) is False) or stop:
                    break
        except (KeyboardInterrupt, _gi.RenderCancelled):
            if result is None:
                raise
        finally:
            if isinstance(report, ProgressBar):
                report.close()
        return result

    @property
    def animation_duration(self) -> float | None:
        """Length of the scene's animation in seconds (``None``: the scene has none)."""
        return self._scene.animation_duration

    def apply_animation(self, time: float) -> None:
        """Poses the scene at ``time`` seconds of its ``animation`` tracks: every animated
        camera, light, object and material takes its description at that time (the fields
        no track animates keep the scene file's values). Nothing happens without tracks."""
        from gi.animation import animation_updates

        self.update(**animation_updates(self._scene, time))

    def render_animation(
        self,
        frames: Iterable[int] | None = None,
        fps: float = 30.0,
        *,
        aovs: bool = False,
        extras: bool = False,
        seed: int | None = None,
        progress: bool | ProgressCallback = False,
    ) -> Iterator[tuple[int, RenderResult]]:
        """Renders frames of the scene's animation: an iterator of ``(frame number,
        RenderResult)``. Frame ``n`` shows time ``n / fps`` seconds (:meth:`apply_animation`
        before each frame); ``frames`` defaults to the whole animation,
        ``range(round(duration · fps))``. ``progress=True`` draws one bar over the frames on
        stderr when it is a terminal; a callable gets ``("frames", fraction done)`` and
        cancels with :class:`gi.RenderCancelled` by returning ``False``. Arguments are checked
        at the call (:class:`gi.SettingError`), before any frame is rendered.

        >>> for n, frame in r.render_animation(range(0, 120), fps=30):
        ...     gi.save_image(f"frame_{n:04d}.png", frame.radiance)
        """
        from gi.animation import render_frames

        return render_frames(
            self,
            self._scene,
            frames,
            fps,
            aovs=aovs,
            extras=extras,
            seed=seed,
            progress=progress,
        )


def _jsonable(value: Any) -> Any:
    """numpy arrays (a 4×4 matrix) as nested lists."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def render(
    scene: Scene,
    method: str = "path",
    *,
    spp: int | None = None,
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
    edge_supersampling: bool = True,
    volume_shape: str = "auto",
    estimator: str = "auto",
    first_bounce: str = "auto",
    adapter: str | None = None,
    shadow_map_size: int = 1024,
    caustic_density_bound: bool = True,
    photon_focus: float = 0.25,
    vpls_per_light: int = 64,
    rsm_size: int = 64,
    vpl_shadow_map_size: int = 128,
    bundles: int = 16,
    bundle_resolution: int = 128,
    bundle_memory_mb: int = 64,
    bidir_strategy: str = "mis",
    roughness_clamping: bool = True,
    progress: bool | ProgressCallback = False,
    denoise: bool = False,
) -> RenderResult:
    """Renders ``scene`` with ``method`` (see :func:`gi.methods`).

    ``size`` is ``(width, height)`` and defaults to the scene camera's. ``spp`` is camera
    samples per pixel (default 64; 16 direct-light samples for the GPU methods ``direct`` and
    ``ispm``, chosen by measurement); ``light_paths`` the caustic light paths of method ``path``
    (default one per camera sample). Method ``photon`` (classic photon mapping) emits
    ``photons`` photons and estimates radiance from the ``k`` nearest within ``max_radius``
    (metres; default 5% of the scene's diagonal) with a ``kernel`` of "box", "cone" or
    "epanechnikov".
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
    edges and corners keep their energy (for ``gather`` too, on its footprints). Mirrors
    and glass seen by the camera are traced backwards on the CPU with a photon-map gather
    (``k``, ``max_radius``, ``kernel``). ``volume_shape`` picks the shape drawn per photon
    volume: "icosahedron", "quad" (a screen-aligned bounding rectangle, cheaper for
    small volumes) or "auto" (quads for volumes under 16 pixels in radius, else icosahedra);
    it changes the cost, not the image. ``estimator`` picks how the photons are splatted:
    "volumes" (the rasterizer draws the volumes), "tiled" (compute passes bin the photons to
    screen tiles), "cluster" (a hierarchy over the view samples with whole nodes accepted at
    once; Moreau et al. 2016), all three the same image up to float rounding; "directional"
    (the cluster hierarchy's approximation: per-cluster irradiance from 8 directions,
    faster, blockier), "cpu" (the tiled estimate computed on the CPU, the same image; fastest
    on CPU devices) or "auto" (per adapter; ``stats.estimator_reason`` says why).
    ``first_bounce`` picks where ``ispm`` finds its photons' first hits: "raster" (the bounce
    maps), "traced" (the same photons cast from the lights in the CPU BVH, cheaper on a CPU
    rasterizer) or "auto" ("traced" on CPU devices such as lavapipe, else "raster"); the
    photons have the same distribution either way.
    GPU methods (``direct``, ``ispm``, ``bidir``) run on ``adapter`` ("cpu" for lavapipe,
    "gpu", or part of an adapter's name; default: the ``GI_ADAPTER`` environment variable,
    else a real GPU when present, else lavapipe) with ``shadow_map_size``² texels per
    shadow-map face. Their direct light is supersampled ``spp`` times only at pixels on
    silhouettes, creases and material boundaries and shaded once at the centre elsewhere
    (box-filtered over the pixel's footprint); ``edge_supersampling=False`` supersamples
    every pixel (a full-screen pass per sample: the same image to ~1e-4, 6–9× slower).
    ``caustic_density_bound`` (methods ``ispm`` and ``gather``) keeps each caustic photon's
    kernel radius within 0.75–1.5 times the distance to its 16th nearest caustic photon, so
    caustic kernels are small where caustics focus and wide where they spread.
    ``photon_focus`` aims that share of each light's photons at the mirrors and glass
    through a projection map, weighted so that the image is unchanged (method ``ispm``:
    those aimed photons, traced on the CPU, carry every first hit on a mirror or glass).
    Method ``bidir`` (Tokuyoshi & Ogaki 2012, bidirectional path tracing by rasterization)
    adds to the GPU direct light the indirect light of ``vpls_per_light`` virtual point lights
    per light (drawn by flux from reflective shadow maps of about ``rsm_size``² texels per
    view, each with a cube shadow map of ``vpl_shadow_map_size``² texels per face) and of
    ``bundles`` global ray bundles per frame (the scene rasterized along random directions at
    ``bundle_resolution``² pixels into fragment lists of ``bundle_memory_mb`` MiB; fragments
    beyond it are dropped and counted in ``stats.bundle_overflow``), combined by multiple
    importance sampling (``bidir_strategy`` "mis"; "vpl" or "bundle" for one strategy alone),
    with a clamped two-bounce term when ``max_depth`` ≥ 3 and, with ``roughness_clamping``,
    glossy lobes widened where samples are sparse. It lights scenes with an environment
    light through the bundles (direct light from the sky; 3/4 of the bundle directions
    drawn from an image sky's luminance).
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
            raise SettingError(INSTALL_HINT)
    renderer = Renderer(
        scene,
        method,
        spp=spp,
        size=size,
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
        edge_supersampling=edge_supersampling,
        volume_shape=volume_shape,
        estimator=estimator,
        first_bounce=first_bounce,
        adapter=adapter,
        shadow_map_size=shadow_map_size,
        caustic_density_bound=caustic_density_bound,
        photon_focus=photon_focus,
        vpls_per_light=vpls_per_light,
        rsm_size=rsm_size,
        vpl_shadow_map_size=vpl_shadow_map_size,
        bundles=bundles,
        bundle_resolution=bundle_resolution,
        bundle_memory_mb=bundle_memory_mb,
        bidir_strategy=bidir_strategy,
        roughness_clamping=roughness_clamping,
    )
    result = renderer.render(aovs=True, extras=True, progress=progress)
    if denoise:
        from gi.denoising import denoise as run_denoiser

        result = run_denoiser(result)
    return result
