"""The typed rendering entry point over the native module."""

from __future__ import annotations

import json
import math
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gi import _checks, _gi
from gi._gi import RenderStats, RenderWarning, Scene, SettingError
from gi.progress import ProgressBar

ProgressCallback = Callable[[str, float], "bool | None"]


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


def _options(options: dict[str, Any]) -> dict[str, Any]:
    """Render options for the native module, with ``size`` split into width and height."""
    size = options.pop("size", None)
    if size is not None:
        try:
            options["width"], options["height"] = size
        except (TypeError, ValueError):
            raise _checks.setting_error("size", f"expected (width, height), got {size!r}") from None
    return options


def options_table(method: str | None = None) -> list[dict[str, Any]]:
    """The render options (the core's table): one dict per option with ``name``, ``kind``
    ("bool", "int", "float", "choice", "text"), ``default``, ``optional`` (``None`` allowed,
    meaning automatic), ``range`` (the values taken, in words), ``min``/``max`` or
    ``choices``, ``methods`` and ``doc``. With ``method``, only the options it takes (one
    row per name). ``gi.render``, ``gi.Renderer``, the CLI and batch jobs take exactly
    these (and ``size=(width, height)`` for width and height)."""
    rows = _gi.options()
    if method is None:
        return rows
    if method not in _gi.methods():
        raise _checks.setting_error(
            "method", f"unknown method {method!r} (available: {', '.join(_gi.methods())})"
        )
    return [row for row in rows if method in row["methods"]]


def _progress(progress: bool | ProgressCallback) -> ProgressCallback | None:
    if progress is True:
        return ProgressBar()
    if progress is False or progress is None:
        return None
    if not callable(progress):
        raise _checks.setting_error("progress", f"must be a bool or a callable, got {progress!r}")
    return progress


def _result(out: dict[str, Any]) -> RenderResult:
    return RenderResult(
        radiance=out["radiance"],
        albedo=out["albedo"],
        normal=out["normal"],
        position=out["position"],
        depth=out["depth"],
        caustics=out["caustics"],
        stats=out["stats"],
        extra=dict(out["extra"]),
    )


class Renderer:
    """A persistent renderer: made once from a scene, a method and its options (the
    keywords of :func:`render`; :func:`gi.options_table` lists them), then one
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

    def __init__(self, scene: Scene, method: str = "ispm", **options: Any) -> None:
        if not isinstance(method, str):
            raise _checks.setting_error("method", f"must be a string, got {method!r}")
        self._native = _gi.Renderer(scene, method, _options(options))
        self._scene = scene
        for message in self._native.warnings:
            warnings.warn(message, RenderWarning, stacklevel=_caller_level())

    @property
    def method(self) -> str:
        return self._native.method

    @property
    def options(self) -> dict[str, Any]:
        """Every option of the method with its value (given, or the table's default)."""
        return self._native.options  # type: ignore[no-any-return]

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
        in the scene format; ``"object"`` (key: index or name) as ``{"name", "matrix"
        (4×4 rows, what :meth:`update` takes), "triangles": [start, end]}`` (its range of
        ``Scene.mesh_arrays()``' triangles)."""
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
            self._native.update("camera", None, _update_json(camera, "camera"))
        for i, light in (lights or {}).items():
            self._native.update("light", i, _update_json(light, f"lights[{i}]"))
        for key, transform in (objects or {}).items():
            where = f"objects[{key}].transform"
            self._native.update("object", key, _update_json(_jsonable(transform), where))
        for name, material in (materials or {}).items():
            self._native.update("material", name, _update_json(material, f"materials.{name}"))

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


def _update_json(value: Any, where: str) -> str:
    """An update's fields as JSON; a NaN or infinite number (which JSON cannot hold) is a
    :class:`gi.SceneError` naming its field, as the core names the fields it rejects."""
    try:
        return json.dumps(value, allow_nan=False)
    except ValueError:
        pass
    from gi.meshes import scene_error

    items = value.items() if isinstance(value, dict) else [("", value)]
    for key, v in items:
        try:
            json.dumps(v, allow_nan=False)
        except ValueError:
            field = f"{where}.{key}" if key else where
            raise scene_error("scene update", field, "must be finite") from None
    raise scene_error("scene update", where, "must be finite")


def _jsonable(value: Any) -> Any:
    """numpy arrays (a 4×4 matrix) as nested lists."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def method_options(method: str, **options: Any) -> dict[str, Any]:
    """The ``options`` that ``method`` takes (with ``size``), the rest dropped: for sweeps
    that share options across methods, which would otherwise warn for each option a
    method ignores."""
    names = {row["name"] for row in options_table(method)} | {"size"}
    return {name: value for name, value in options.items() if name in names}


def render(
    scene: Scene,
    method: str = "path",
    *,
    progress: bool | ProgressCallback = False,
    denoise: bool = False,
    **options: Any,
) -> RenderResult:
    """Renders ``scene`` with ``method`` (see :func:`gi.methods`): one frame of a
    :class:`Renderer` with every image read back.

    ``options`` are the method's render options (listed below, and by
    :func:`gi.options`); ``size=(width, height)`` sets width and height. An option that
    does not apply to the method is ignored with a :class:`gi.RenderWarning`.
    ``progress`` is a callable ``(stage, fraction) -> bool | None`` (return ``False`` to
    cancel), or ``True`` for progress bars (tqdm; in a terminal or a notebook, nothing in
    logs). The GIL is released while rendering; Ctrl-C cancels with
    :class:`KeyboardInterrupt`. ``denoise`` runs Intel Open Image Denoise on the radiance,
    guided by the albedo and normal AOVs (:func:`gi.denoise`); the noisy radiance is kept
    as the AOV ``noisy``.
    """
    if denoise:
        from gi.denoising import INSTALL_HINT, available

        if not available():
            raise SettingError(INSTALL_HINT)
    renderer = Renderer(scene, method, **options)
    result = renderer.render(aovs=True, extras=True, progress=progress)
    if denoise:
        from gi.denoising import denoise as run_denoiser

        result = run_denoiser(result)
    return result


def _option_docs() -> str:
    """The options of :func:`render` and :class:`Renderer`, from the core's table."""
    lines = ["Options (default; methods):", ""]
    for row in _gi.options():
        default = "None" if row["default"] is None else repr(row["default"])
        methods = ", ".join(row["methods"])
        lines.append(f"- ``{row['name']}`` ({default}; {methods}): {row['doc']}")
    return "\n".join(lines)


render.__doc__ = f"{render.__doc__}\n{_option_docs()}\n"


def _caller_level() -> int:
    """``stacklevel`` of a warning that names the first frame outside the package."""
    frame = sys._getframe(1)
    level = 1
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level


_PACKAGE_DIR = str(Path(__file__).parent)
