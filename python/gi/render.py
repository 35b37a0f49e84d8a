"""The typed rendering entry point over the native module."""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from gi import _checks, _gi
from gi._gi import RenderWarning, Scene, SceneError, SettingError
from gi.animation import animation_updates, render_frames
from gi.denoising import INSTALL_HINT, available
from gi.denoising import denoise as run_denoiser
from gi.display import check_tonemap, to_srgb8
from gi.meshes import scene_error
from gi.progress import ProgressBar
from gi.result import RenderResult
from gi.scene import TEXTURE_FIELDS, SceneWarning, load_scene

ProgressCallback = Callable[[str, float], "bool | None"]

#: The method of every entry point that is given none (:func:`render`, :class:`Renderer`,
#: ``gi render``, ``gi view``, :func:`gi.view`, batch jobs): ``ispm``, the renderer's own
#: method, real-time on a GPU and the interactive one in the viewer. ``path`` is the
#: reference, to be asked for by name (it is the slowest at equal settings).
DEFAULT_METHOD = "ispm"


def _options(options: dict[str, Any]) -> dict[str, Any]:
    """Render options for the native module, with ``size`` split into width and height."""
    size = options.pop("size", None)
    if size is not None:
        try:
            options["width"], options["height"] = size
        except (TypeError, ValueError):
            raise _checks.setting_error(
                "size", f"expected (width, height), each in 1..=16384, got {size!r}"
            ) from None
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


def _scene(scene: Any) -> Scene:
    """``scene``, or the scene a built-in name or file names (:func:`gi.load_scene`)."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(scene)
    raise _checks.setting_error(
        "scene",
        f"expected a gi.Scene, a built-in scene name or a scene file, got {scene!r}",
    )


#: How to light a scene that has no light of its own; every "no light" message ends so.
LIGHT_HINT = (
    "light it with an environment: `gi render SCENE --env FILE.hdr` (or `--env sky`),"
    " environment= in gi.render / gi.Renderer, or the viewer's Environment panel"
)


def _warn_if_black(scene: Scene) -> None:
    """A :class:`gi.SceneWarning` for a scene that renders black (no light source with
    power: lights, emitting surfaces, an environment) or nearly black (a glTF asset without
    lights or an environment, lit only by its emissive surfaces: glTF assets are made to be
    lit by the viewer's environment), or that has nothing to see."""
    gltf = Path(scene.source).suffix.lower() in (".gltf", ".glb")
    if max(scene.total_power) <= 0.0:
        reason = (
            "the scene has no light source with power (lights, emitting surfaces or an"
            f" environment): the image is black; {LIGHT_HINT}"
        )
        warnings.warn(SceneWarning(scene.source, "lights", reason), stacklevel=_caller_level())
    elif gltf and scene.light_count == 0 and not scene.has_environment:
        reason = (
            "the glTF file has no lights and gi no environment: only its emissive surfaces"
            f" light it and the image is nearly black; {LIGHT_HINT}"
        )
        warnings.warn(SceneWarning(scene.source, "lights", reason), stacklevel=_caller_level())
    if scene.triangle_count == 0 and not scene.has_environment:
        reason = "the scene has no objects: there is nothing to see and the image is black"
        warnings.warn(SceneWarning(scene.source, "objects", reason), stacklevel=_caller_level())


def _flag(name: str, value: Any) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise _checks.setting_error(name, f"must be True or False, got {value!r}")


def _progress(progress: bool | ProgressCallback) -> ProgressCallback | None:
    if progress is True:
        return ProgressBar()
    if progress is False or progress is None:
        return None
    if not callable(progress):
        raise _checks.setting_error("progress", f"must be a bool or a callable, got {progress!r}")
    return progress


def _result(out: dict[str, Any]) -> RenderResult:
    half = out.get("radiance_half")
    return RenderResult(
        radiance=out["radiance"] if half is None else half.view(np.float16),
        albedo=out["albedo"],
        normal=out["normal"],
        position=out["position"],
        depth=out["depth"],
        caustics=out["caustics"],
        stats=out["stats"],
        extra=dict(out["extra"]),
        display8=out.get("display", np.zeros((0, 0, 3), np.uint8)),
    )


#: ``radiance=`` of :meth:`Renderer.render`.
RADIANCE_FORMATS = ("float32", "float16", None)
#: Tone maps the core applies (on the GPU where the frame allows); the rest in Python.
_CORE_TONEMAPS = ("clip", "filmic", "agx")


def _readout(radiance: Any, tonemap: Any, exposure: Any) -> tuple[str | None, str | None, float]:
    """Checked ``radiance``, ``tonemap`` and ``exposure`` of :meth:`Renderer.render`."""
    if not (radiance is None or (isinstance(radiance, str) and radiance in RADIANCE_FORMATS)):
        raise _checks.setting_error(
            "radiance", f"must be 'float32', 'float16' or None, got {radiance!r}"
        )
    if tonemap is not None:
        check_tonemap(tonemap)
    return radiance, tonemap, _checks.exposure_setting(exposure)


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

    def __init__(
        self,
        scene: Scene | str | os.PathLike[str],
        method: str = DEFAULT_METHOD,
        *,
        environment: Any = None,
        **options: Any,
    ) -> None:
        from gi.lighting import with_environment

        scene = with_environment(_scene(scene), environment)
        if not isinstance(method, str):
            methods = ", ".join(_gi.methods())
            raise _checks.setting_error("method", f"must be one of {methods}; got {method!r}")
        self._native = _gi.Renderer(scene, method, _options(options))
        self._scene = scene
        self._pass_seconds = 0.0
        # Object transforms as last given to update() (index -> translate/rotate/scale),
        # which describe() gives back as they were given (295°, not the -65° that taking
        # the matrix apart yields); a matrix update drops the object's entry.
        self._given_transforms: dict[int, dict[str, Any]] = {}
        for message in self._native.warnings:
            warnings.warn(message, RenderWarning, stacklevel=_caller_level())
        _warn_if_black(scene)

    def __repr__(self) -> str:
        w, h = self.size
        mode = ""
        if self._native.progressive:
            mode = f", progressive ({self.passes} passes)"
        return (
            f"<gi.Renderer {self.method} {w}x{h} of {self._scene.source!r}{mode},"
            f" {self.frame_index} frames rendered>"
        )

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
        in the scene format, what :meth:`update` takes; ``"object"`` (key: index or name) as
        ``{"name", "transform", "matrix", "triangles"}``: its ``transform`` in the scene
        format (``translate``/``rotate``/``scale`` as the scene file or the last
        :meth:`update` gave them, angles included: ``rotate: [0, 295, 0]`` reads back as
        295, not as the -65 of the same rotation; after a ``matrix`` update, the matrix
        taken apart; ``None`` for a matrix with shear, which they cannot describe) and
        ``matrix`` (4×4 rows), either of which :meth:`update` takes, and ``triangles``
        ``[start, end]``, its range of ``Scene.mesh_arrays()``' triangles."""
        targets = ("camera", "light", "object", "material")
        if not isinstance(target, str) or target not in targets:
            raise _checks.setting_error(
                "target", f"must be one of {', '.join(targets)}; got {target!r}"
            )
        if target == "object":
            key = self._object_index(key, "describe")
        elif target == "light":
            key = self._light_index(0 if key is None else key, "describe")
        elif target == "material" and not (
            isinstance(key, str) and key in self._scene.material_names
        ):
            names = ", ".join(self._scene.material_names)
            raise _checks.setting_error("key", f"must be a material's name ({names}), got {key!r}")
        desc = self._native.describe(target, key)
        if target == "object" and desc.get("transform") is not None:
            i = self.object_names.index(key) if isinstance(key, str) else key
            desc["transform"] = dict(self._given_transforms.get(i, desc["transform"]))
        if target == "material":
            desc = _texture_names_out(desc)
        return desc  # type: ignore[no-any-return]

    def _light_index(self, key: Any, field: str) -> int:
        """``key`` as a light's index; else a :class:`gi.SceneError` for ``field`` of an
        update (``lights[i]`` for an index out of range), or a :class:`gi.SettingError`
        for ``key`` of :meth:`describe`."""
        n = self._scene.light_count
        integer = not isinstance(key, bool) and isinstance(key, numbers.Integral)
        if not integer or not 0 <= key < n:
            lights = f"0..={n - 1}" if n else "none: the scene has no lights"
            if integer and field == "lights":
                field = f"lights[{key}]"
            raise _key_error(field, f"must be a light's index ({lights}), got {key!r}")
        return int(key)

    def _object_index(self, key: Any, field: str) -> int | str:
        """``key`` as an object's name or index (see :meth:`_light_index`)."""
        names = self.object_names
        if isinstance(key, str):
            if key not in names:
                named = ", ".join(repr(n) for n in names if n is not None) or "none"
                raise _key_error(field, f"no object named {key!r} (named objects: {named})")
            return key
        n = len(names)
        if isinstance(key, bool) or not isinstance(key, numbers.Integral) or not 0 <= key < n:
            indices = f"0..={n - 1}" if n else "none: the scene has no objects"
            raise _key_error(field, f"must be an object's name or index ({indices}), got {key!r}")
        return int(key)

    def update(
        self,
        *,
        camera: dict[str, Any] | None = None,
        lights: dict[int, dict[str, Any]] | None = None,
        objects: dict[int | str, dict[str, Any]] | None = None,
        materials: dict[str, dict[str, Any]] | None = None,
        environment: Any = None,
    ) -> None:
        """Changes the scene before the next frame, in the scene format's terms.

        ``environment`` lights the scene as :mod:`gi.lighting` describes (a file, an array,
        ``"sky"`` or a dict with strength, rotation, sun and mode), starting from the
        scene's own lights and environment as loaded (calls do not accumulate; light
        updates made before it are dropped); ``"none"`` gives the scene its own light back.
        The GPU methods keep their scene on the GPU and upload the environment's tables and
        the lights (a lighting with another number of lights or shadow maps builds it anew).

        ``camera`` and each ``lights[i]``, ``objects[name or index]`` and
        ``materials[name]`` give the fields that change (``{"position": [0, 1, 3]}``); the
        others keep their current values (see :meth:`describe`). An object's fields are its
        transform's: ``translate``/``rotate``/``scale`` as in the scene file, or
        ``{"matrix": 4×4 rows}`` for the whole transform. A light given another ``type``
        keeps the fields both types have (a spot turned point light its position and
        intensity). The camera's ``width``/``height`` belong to the
        renderer (:meth:`resize`). Material textures are named as in the scene file (the
        file name relative to it) and must be among the textures the scene loaded. Values
        may be numpy arrays and scalars. Invalid values raise :class:`gi.SceneError` naming
        the field and what it allows.
        """
        groups = {"lights": lights, "objects": objects, "materials": materials}
        if camera is not None and not isinstance(camera, Mapping):
            raise _update_error("camera", f"must be a dict of camera fields, got {camera!r}")
        for group, value in groups.items():
            if value is not None and not isinstance(value, Mapping):
                what = {"lights": "a light's index", "objects": "an object's index or name"}
                key = what.get(group, "a material's name")
                raise _update_error(
                    group, f"must be a dict from {key} to its fields, got {value!r}"
                )
        if environment is not None:
            self._set_environment(environment)
        if camera is not None:
            self._native.update("camera", None, _fields("camera", camera))
        for i, light in (lights or {}).items():
            i = self._light_index(i, "lights")
            self._native.update("light", i, _fields(f"lights[{i}]", light))
        for key, transform in (objects or {}).items():
            key = self._object_index(key, "objects")
            i = self.object_names.index(key) if isinstance(key, str) else key
            given = _fields(f"objects[{i}].transform", transform)
            before = self.describe("object", i)["transform"] or {}
            self._native.update("object", key, given)
            if "matrix" in given:
                self._given_transforms.pop(i, None)
            else:
                self._given_transforms[i] = {**before, **given}
        for name, material in (materials or {}).items():
            if not isinstance(name, str):
                names = ", ".join(self._scene.material_names)
                raise _update_error("materials", f"a material's name ({names}), got {name!r}")
            material = self._texture_names_in(name, material)
            self._native.update("material", name, _fields(f"materials.{name}", material))

    def _set_environment(self, environment: Any) -> None:
        from gi.lighting import Lighting

        if isinstance(environment, str) and environment == "none":
            self._native.set_lighting(None, None, None, True)
            return
        self._native.set_lighting(**Lighting(environment).native_args())

    def _texture_names_in(self, name: str, material: Any) -> Any:
        """A material update's texture names (as in the scene file) as the scene loaded
        them: data maps (roughness, normal, alpha) carry the suffix ``#linear``."""
        if not isinstance(material, Mapping):
            return material
        loaded = self._scene.texture_names
        out = dict(material)
        for key, colour in TEXTURE_FIELDS.items():
            value = out.get(key)
            if not isinstance(value, str):
                continue
            candidates = [value] if colour else [f"{value}#linear", value]
            found = next((c for c in candidates if c in loaded), None)
            if found is None:
                shown = sorted({t.removesuffix("#linear") for t in loaded})
                raise _update_error(
                    f"materials.{name}.{key}",
                    f"no texture {value!r} was loaded (loaded: {', '.join(shown) or 'none'});"
                    " an update can use the textures the scene loaded, named as in the scene"
                    " file",
                )
            out[key] = found
        return out

    def resize(self, width: int, height: int) -> None:
        """Changes the image size, each side in 1..=16384 pixels (render targets are rebuilt
        at the next frame)."""
        self._native.resize(width, height)

    def render(
        self,
        *,
        aovs: bool = False,
        extras: bool = False,
        seed: int | None = None,
        progress: bool | ProgressCallback = False,
        radiance: str | None = "float32",
        tonemap: str | None = None,
        exposure: float = 0.0,
    ) -> RenderResult:
        """Renders one frame. Only the radiance is read back unless ``aovs`` (albedo,
        normal, position, depth) or ``extras`` (the method's own images) are asked for;
        images not asked for are empty arrays, left out of ``aov_names()``. ``seed`` (in
        0..=2**64-1) overrides the frame's random seed.

        ``radiance`` is the radiance's form: ``"float32"``, ``"float16"`` (a float16 array,
        half the readback) or ``None`` (an empty array). ``tonemap`` (``"clip"``,
        ``"filmic"``/``"agx"``, ``"aces"``; :mod:`gi.display`) with ``exposure`` adds the
        8-bit sRGB image ``display8``: methods ``direct`` and ``ispm`` tone-map it on the GPU
        and read back 4 bytes a pixel instead of 16 (with ``radiance=None`` nothing else);
        the other methods, progressive passes and ``aces`` encode it on the CPU from the
        float radiance, as :func:`gi.display.to_srgb8` does. A progressive renderer's result is
        the mean of its passes: ``stats.passes`` counts them and ``stats.total_seconds`` is
        their time together (the stages are the last pass's, and ``earlier passes``)."""
        report = _progress(progress)
        radiance, tonemap, exposure = _readout(radiance, tonemap, exposure)
        # ACES runs in Python (OpenColorIO): from the 32-bit radiance.
        in_core = tonemap in _CORE_TONEMAPS
        out = self._native.render(
            aovs=_flag("aovs", aovs),
            extras=_flag("extras", extras),
            seed=seed,
            progress=report,
            radiance=radiance if in_core or tonemap is None else "float32",
            tonemap=tonemap if in_core else None,
            exposure=exposure,
        )
        result = _result(out)
        if tonemap is not None:
            if not in_core:
                result = dataclasses.replace(
                    result, display8=to_srgb8(result.radiance, exposure, tonemap)
                )
                if radiance is None:
                    result = dataclasses.replace(result, radiance=np.zeros((0, 0, 3), np.float32))
                elif radiance == "float16":
                    result = dataclasses.replace(
                        result, radiance=result.radiance.astype(np.float16)
                    )
            result = dataclasses.replace(result, display_settings=(tonemap, exposure))
        if self._native.progressive:
            if result.stats.passes <= 1:
                self._pass_seconds = 0.0
            earlier = self._pass_seconds
            self._pass_seconds += result.stats.total_seconds
            if earlier > 0.0:
                stats = result.stats.with_stage("earlier passes", earlier)
                result = dataclasses.replace(result, stats=stats)
        return result

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

        ``seconds`` is kept within a pass: when the time is up, the pass under way is
        cancelled and its work dropped (the first pass always completes, so a first pass
        longer than ``seconds`` overruns by the rest of it). The check runs at the pass's
        progress reports, a few a second in the CPU stages; the GPU-only method
        ``direct`` reports none, its passes being short. Small passes (``spp=1``, 10–80k
        photons) lose less when one is dropped.

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
        if passes is not None and (
            isinstance(passes, bool) or not isinstance(passes, numbers.Integral) or passes < 1
        ):
            raise _checks.setting_error("passes", f"must be an integer >= 1, got {passes!r}")
        if seconds is not None and not (
            not isinstance(seconds, bool)
            and isinstance(seconds, numbers.Real)
            and math.isfinite(seconds)
            and seconds > 0
        ):
            raise _checks.setting_error("seconds", f"must be a finite number > 0, got {seconds!r}")
        _flag("aovs", aovs)
        _flag("extras", extras)
        if on_pass is not None and not callable(on_pass):
            raise _checks.setting_error("on_pass", f"must be a callable or None, got {on_pass!r}")
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
            # The time is kept within a pass: once it is up, the pass under way is cancelled
            # (the passes done so far are returned), unless it is the first.
            if seconds is not None and result is not None:
                if time.monotonic() - start >= seconds:
                    return False
            # The bar follows the run, not the stages of a pass; a False from the callback
            # cancels the pass at once (the passes done so far are returned).
            if report is None:
                return True
            return report("passes", min(done_fraction(), 0.999)) is not False

        try:
            while result is None or done_fraction() < 1.0:
                result = self.render(aovs=aovs, extras=extras, progress=within_pass)
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


def render_animation(
    scene: Scene,
    method: str = DEFAULT_METHOD,
    frames: Iterable[int] | None = None,
    fps: float = 30.0,
    *,
    aovs: bool = False,
    extras: bool = False,
    progress: bool | ProgressCallback = False,
    **settings: Any,
) -> Iterator[tuple[int, RenderResult]]:
    """Renders frames of ``scene``'s animation with one :class:`gi.Renderer` (``method`` and
    ``settings`` as for :func:`gi.render`): an iterator of ``(frame number, RenderResult)``.
    See :meth:`gi.Renderer.render_animation`."""
    renderer = Renderer(scene, method, **settings)
    return renderer.render_animation(frames, fps, aovs=aovs, extras=extras, progress=progress)


def _texture_names_out(desc: dict[str, Any]) -> dict[str, Any]:
    """A material description's texture names as the scene file gives them."""
    for key in TEXTURE_FIELDS:
        if isinstance(desc.get(key), str):
            desc[key] = desc[key].removesuffix("#linear")
    return desc


def _update_error(field: str, reason: str) -> SceneError:
    return scene_error("scene update", field, reason)


def _key_error(field: str, reason: str) -> SceneError | SettingError:
    """An update's key (``field``: ``lights``, ``objects``), or :meth:`Renderer.describe`'s
    (``field``: ``describe``) that names nothing in the scene."""
    if field == "describe":
        return _checks.setting_error("key", reason)
    return _update_error(field, reason)


def _plain(value: Any, field: str) -> Any:
    """``value`` with numpy arrays and scalars as lists and numbers, checked for what the
    scene format cannot hold (NaN, infinities, objects): :class:`gi.SceneError` naming the
    field."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise _update_error(field, f"field names are strings, got {k!r}")
            out[k] = _plain(v, f"{field}.{k}")
        return out
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{field}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, float) and not math.isfinite(value):
        raise _update_error(field, f"must be a finite number, got {value}")
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    raise _update_error(field, f"expected a number, string, list or dict, got {value!r}")


def _fields(field: str, value: Any) -> dict[str, Any]:
    """An update's fields as plain Python values (dicts, lists, numbers, strings), what the
    native ``update`` takes."""
    if not isinstance(value, Mapping):
        raise _update_error(field, f"must be a dict of the fields that change, got {value!r}")
    return _plain(value, field)  # type: ignore[no-any-return]


def method_options(method: str, **options: Any) -> dict[str, Any]:
    """The ``options`` that ``method`` takes (with ``size``), the rest dropped: for sweeps
    that share options across methods, which would otherwise warn for each option a
    method ignores."""
    names = {row["name"] for row in options_table(method)} | {"size"}
    return {name: value for name, value in options.items() if name in names}


def render(
    scene: Scene | str | os.PathLike[str],
    method: str = DEFAULT_METHOD,
    *,
    progress: bool | ProgressCallback = False,
    denoise: bool = False,
    environment: Any = None,
    **options: Any,
) -> RenderResult:
    """Renders ``scene`` (a :class:`gi.Scene`, or a built-in name or scene file for
    :func:`gi.load_scene`) with ``method`` (see :func:`gi.methods`; by default
    :data:`DEFAULT_METHOD`, ``ispm``): one frame of a :class:`Renderer` with every image
    read back.

    ``options`` are the method's render options (listed below, and by
    :func:`gi.options`); ``size=(width, height)`` sets width and height. An option that
    does not apply to the method is ignored with a :class:`gi.RenderWarning`.
    ``progress`` is a callable ``(stage, fraction) -> bool | None`` (return ``False`` to
    cancel), or ``True`` for progress bars (tqdm; in a terminal or a notebook, nothing in
    logs). The GIL is released while rendering; Ctrl-C cancels with
    :class:`KeyboardInterrupt`. ``denoise`` runs Intel Open Image Denoise on the radiance,
    guided by the albedo and normal AOVs (:func:`gi.denoise`); the noisy radiance is kept
    as the AOV ``noisy``. ``environment`` lights the scene with an environment image or
    the built-in sky (``"sky"``), added to its light or replacing it (:mod:`gi.lighting`).
    """
    if _flag("denoise", denoise) and not available():
        raise SettingError(INSTALL_HINT)
    renderer = Renderer(scene, method, environment=environment, **options)
    result = renderer.render(aovs=True, extras=True, progress=progress)
    if denoise:
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
