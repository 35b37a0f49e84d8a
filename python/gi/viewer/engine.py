"""The viewer's renderer: one thread that owns the :class:`gi.Renderer` objects, applies
the changes the page and scripts send, renders, and hands each frame to the server.

One render runs at a time however many pages are open: every change goes through
:meth:`Engine.submit` into one queue that the render thread empties before each frame, so
a burst of camera messages becomes one frame showing the last of them. A changed view is
rendered by the interactive renderer (the method and options as given, the rest from the
method's :data:`gi.presets.INTERACTIVE` settings: fewer samples and photons, and for the
CPU methods fewer pixels, so that a frame takes a second or less); once the view has been
still for :data:`REFINE_AFTER` seconds and a page is watching, a second renderer with
``progressive=True`` at the view's full size (small passes:
:data:`gi.presets.PROGRESSIVE_PASS`) adds passes to a running mean (Knaus & Zwicker 2011)
until the next change, which cancels the pass under way. Methods without a progressive
mode (the option table, :func:`gi.options_table`) keep their last frame. Each frame's
``doing`` says which of the two made it, and with what.

Options the method does not take are kept for the methods that do: each renderer made after
the first gets only its method's options (so a method switch in the panel warns of none).
"""

from __future__ import annotations

import concurrent.futures
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

import gi
from gi.aovs import aov_names
from gi.display import TONEMAPS, aov_display, png_bytes, quantize8, to_display
from gi.presets import INTERACTIVE, PROGRESSIVE_PASS, Interactive, describe, with_preset
from gi.render import Renderer, RenderResult, method_options, options_table
from gi.viewer import messages as m
from gi.viewer.environments import EnvironmentFiles
from gi.viewer.picking import ObjectPicker, View, pick_light, translated

#: Seconds a view must stay unchanged before progressive passes start.
REFINE_AFTER = 0.2
_UNCHANGED = object()


@dataclass(frozen=True)
class Frame:
    """A rendered (or re-displayed) frame: 8-bit sRGB pixels, their PNG, and what the page
    shows beside them (``meta``). ``ops`` counts the changes applied before it."""

    id: int
    pixels: np.ndarray
    png: bytes
    meta: dict[str, Any]
    ops: int
    #: Per page (client id): the ``seq`` of its last change that this frame shows.
    seqs: dict[int, int] = field(default_factory=dict)


@dataclass(frozen=True)
class DisplayState:
    exposure: float = 0.0
    tonemap: str = "clip"
    aov: str = "radiance"


@dataclass
class _Slot:
    """A renderer and the scene state it has been given (the change ``version``, size);
    it renders frames of 1/``scale`` of the view's pixels a side."""

    renderer: Renderer
    version: int = 0
    size: tuple[int, int] = (0, 0)
    scale: Interactive = field(default_factory=Interactive)


@dataclass
class _Op:
    message: Any
    client: int | None
    future: concurrent.futures.Future[Any] | None


@dataclass
class _Drag:
    kind: str  # "light" or "object"
    index: int
    anchor: np.ndarray
    start: Any  # light position or object matrix at the pick


class Engine:
    """Renders ``scene`` with ``method`` and ``options`` (the keywords of
    :class:`gi.Renderer`) on its own thread. ``on_frame(frame)`` and ``on_event(client,
    message)`` (``client`` ``None``: every page) are called from that thread."""

    def __init__(
        self,
        scene: gi.Scene,
        method: str,
        options: dict[str, Any],
        *,
        on_frame: Callable[[Frame], None],
        on_event: Callable[[int | None, dict[str, Any]], None],
        display: DisplayState | None = None,
        env_dir: str | Path | None = None,
    ) -> None:
        self._scene = scene
        self._method = method
        # The viewer refines a still view itself (a second, progressive renderer).
        self._options = {k: v for k, v in options.items() if k != "progressive"}
        self._on_frame = on_frame
        self._on_event = on_event
        self._display = display or DisplayState()
        # Made here, so that bad settings fail before anything is served.
        preset = INTERACTIVE.get(method, Interactive())
        given = with_preset(method_options(method, **preset.options), self._options)
        self._interactive = _Slot(Renderer(scene, method, **given), scale=preset)
        self._size = self._interactive.renderer.size
        self._interactive.size = self._size
        self._progressive: _Slot | None = None
        self._progressive_error: str | None = None
        self._pixels = self._size
        self._adapter = _adapter_name(self._options.get("adapter"))
        self._scene_camera = self._interactive.renderer.describe("camera")
        self._light_descs = [
            self._interactive.renderer.describe("light", i) for i in range(scene.light_count)
        ]
        names = self._interactive.renderer.object_names
        self._object_descs = [
            self._interactive.renderer.describe("object", i) for i in range(len(names))
        ]
        self._environment = m.Environment("scene")
        self._env_files = EnvironmentFiles(env_dir)
        self._picker: ObjectPicker | None = None
        self._drag: _Drag | None = None
        # Scene changes since the start, newest value per (target, key) with its version.
        self._version = 0
        self._changes: dict[tuple[str, Any], tuple[int, Any]] = {}
        self._cond = threading.Condition()
        self._ops: list[_Op] = []
        self._submitted = 0
        self._done = 0
        self._stop = False
        self._paused = False
        self._watchers = 0
        self._dirty = True
        self._redisplay = False
        self._last_change = time.monotonic()
        self._result: RenderResult | None = None
        self._result_meta: dict[str, Any] = {}
        self._frame: Frame | None = None
        self._frame_ops = 0
        self._frame_id = 0
        self._seqs: dict[int, int] = {}
        self._thread = threading.Thread(target=self._run, name="gi-view-render", daemon=True)

    # Called from other threads ------------------------------------------------------------

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout: float = 1.5) -> None:
        """Cancels the frame under way and ends the render thread."""
        with self._cond:
            self._stop = True
            self._cond.notify_all()
        if self._thread.is_alive():
            self._thread.join(timeout)

    def submit(
        self, message: Any, client: int | None = None, *, wait: bool = False
    ) -> concurrent.futures.Future[Any] | None:
        """Queues a parsed message (:mod:`gi.viewer.messages`) for the render thread. With
        ``wait`` a future is returned: its result is set once the change is applied (or its
        exception, a :class:`gi.GiError`)."""
        future: concurrent.futures.Future[Any] | None = (
            concurrent.futures.Future() if wait else None
        )
        with self._cond:
            if self._stop:
                raise gi.RenderCancelled("the viewer is stopping")
            self._ops.append(_Op(message, client, future))
            self._submitted += 1
            self._cond.notify_all()
        return future

    def set_watchers(self, count: int) -> None:
        """How many pages are open: progressive passes run only while one is."""
        with self._cond:
            self._watchers = count
            self._cond.notify_all()

    def wait_frame(self, timeout: float) -> Frame | None:
        """The current frame once it shows every change submitted before this call (paused:
        the last frame); ``None`` after ``timeout`` seconds without one."""
        deadline = time.monotonic() + timeout
        with self._cond:
            wanted = self._submitted
            while not self._stop:
                if self._frame is not None and (self._frame_ops >= wanted or self._paused):
                    return self._frame
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(left)
        return None

    def latest(self) -> Frame | None:
        """The newest frame, whatever it shows."""
        with self._cond:
            return self._frame

    def state(self, source: int | None = None) -> dict[str, Any]:
        """What the page shows besides the frame: camera, lights, settings, choices."""
        with self._cond:
            return self._state_locked(source)

    # The render thread --------------------------------------------------------------------

    def _run(self) -> None:
        try:
            while True:
                with self._cond:
                    while not self._stop and not self._work_locked():
                        self._cond.wait(self._wait_locked())
                    if self._stop:
                        break
                    ops, self._ops = self._ops, []
                changed_by = {self._apply(op) for op in ops} - {_UNCHANGED}
                if changed_by:
                    # Pages keep their own camera while they move it, so they take the
                    # camera of a state that another page caused (source None: everyone).
                    only = changed_by.pop() if len(changed_by) == 1 else None
                    source = only if isinstance(only, int) else None
                    self._on_event(None, {**self.state(source), "type": "state"})
                with self._cond:
                    if not (self._dirty or self._redisplay):
                        self._frame_ops = max(self._frame_ops, self._done)
                        self._cond.notify_all()
                    paused = self._paused
                if paused:
                    continue
                if self._dirty:
                    self._render(self._interactive, progressive=False)
                elif self._redisplay:
                    self._show(self._result, self._result_meta)
                elif self._refine_due():
                    self._refine()
        except Exception as e:  # a bug: tell the pages rather than die silently
            self._on_event(None, {"type": "error", "message": f"viewer stopped: {e!r}"})
            raise
        finally:
            with self._cond:
                self._stop = True
                for op in self._ops:
                    if op.future is not None:
                        op.future.set_exception(gi.RenderCancelled("the viewer stopped"))
                self._ops = []
                self._cond.notify_all()

    def _work_locked(self) -> bool:
        if self._ops:
            return True
        if self._paused:
            return False
        return self._dirty or self._redisplay or self._refine_due()

    def _wait_locked(self) -> float | None:
        if self._paused or not self._can_refine():
            return None
        return max(REFINE_AFTER - (time.monotonic() - self._last_change), 0.01)

    def _can_refine(self) -> bool:
        return self._watchers > 0 and self._progressive_error is None and self._result is not None

    def _refine_due(self) -> bool:
        return self._can_refine() and time.monotonic() - self._last_change >= REFINE_AFTER

    def _cancel_requested(self, progressive: bool) -> bool:
        """Polled by a frame under way: stop it when the viewer stops, and stop a
        progressive pass when a change arrives (the pass would show the old view)."""
        with self._cond:
            if self._stop:
                return True
            return progressive and any(not isinstance(o.message, m.Ack) for o in self._ops)

    # Changes ------------------------------------------------------------------------------

    def _apply(self, op: _Op) -> int | None | object:
        """Applies one message; returns who changed the state (the client, ``None`` for
        everyone) or ``_UNCHANGED``."""
        msg = op.message
        changed_by: int | None | object = _UNCHANGED
        try:
            result = self._dispatch(msg, op.client)
            if not isinstance(msg, m.Pick):
                changed_by = None if isinstance(msg, m.ResetView) else op.client
        except (gi.GiError, ValueError) as e:
            self._report(op.client, e)
            result = e
        finally:
            with self._cond:
                self._done += 1
        if op.future is not None:
            if isinstance(result, BaseException):
                op.future.set_exception(result)
            else:
                op.future.set_result(result)
        seq = getattr(msg, "seq", None)
        if seq is not None and op.client is not None:
            self._seqs[op.client] = seq
        return changed_by

    def _dispatch(self, msg: Any, client: int | None) -> Any:
        if isinstance(msg, m.Camera):
            self._update("camera", None, msg.camera)
        elif isinstance(msg, m.ResetView):
            fields = {k: self._scene_camera[k] for k in ("position", "look_at", "up", "fov")}
            self._update("camera", None, fields)
        elif isinstance(msg, m.Lights):
            for i, fields in msg.lights.items():
                self._update("light", i, fields)
        elif isinstance(msg, m.Objects):
            for key, transform in msg.objects.items():
                self._update("object", key, transform)
        elif isinstance(msg, m.Materials):
            for name, fields in msg.materials.items():
                self._update("material", name, fields)
        elif isinstance(msg, m.Environment):
            self._update("environment", None, msg.spec(self._env_files.path))
            self._environment = msg
        elif isinstance(msg, m.Settings):
            self._change_settings(msg.settings)
        elif isinstance(msg, m.Display):
            self._change_display(msg)
        elif isinstance(msg, m.Resize):
            if (msg.width, msg.height) != self._size:
                self._size = (msg.width, msg.height)
                self._changed()
        elif isinstance(msg, m.Pause):
            with self._cond:
                self._paused = msg.paused
            self._last_change = time.monotonic()
        elif isinstance(msg, m.Pick):
            return self._pick(msg, client)
        elif isinstance(msg, m.Drag):
            self._drag_to(msg)
        elif isinstance(msg, m.Drop):
            self._drag = None
        else:
            raise m.MessageError("type", f"not a change: {type(msg).__name__}")
        return None

    def _update(self, target: str, key: Any, fields: dict[str, Any]) -> None:
        """Applies one scene change to the interactive renderer (which checks it) and
        records the whole resulting description for the progressive one."""
        r = self._sync(self._interactive)
        r.update(**_update_arguments(target, key, fields))
        if target == "environment":
            value: Any = fields
        elif target == "camera":
            value = {k: v for k, v in r.describe("camera").items() if k not in ("width", "height")}
        elif target == "light":
            value = r.describe("light", key)
            self._light_descs[key] = value
        elif target == "object":
            desc = r.describe("object", key)
            key = key if isinstance(key, int) else r.object_names.index(key)
            self._object_descs[key] = desc
            value = {"matrix": desc["matrix"]}
        else:
            value = r.describe("material", key)
        self._version += 1
        self._changes[(target, key)] = (self._version, value)
        self._interactive.version = self._version
        self._changed()

    def _changed(self) -> None:
        self._dirty = True
        self._last_change = time.monotonic()

    def _sync(self, slot: _Slot) -> Renderer:
        """Brings a renderer up to the current scene changes and size."""
        r = slot.renderer
        for (target, key), (version, value) in self._changes.items():
            if version > slot.version:
                r.update(**_update_arguments(target, key, value))
        slot.version = self._version
        size = slot.scale.size(*self._size)
        if slot.size != size:
            r.resize(*size)
            slot.size = size
        return r

    def _change_settings(self, changes: dict[str, Any]) -> None:
        method = changes.get("method", self._method)
        options = dict(self._options)
        for k, v in changes.items():
            if k == "method":
                continue
            if v is None:
                options.pop(k, None)
            else:
                options[k] = v
        preset = INTERACTIVE.get(method, Interactive())
        renderer = self._renderer(method, options, progressive=False)  # SettingError
        slot = _Slot(renderer, size=renderer.size, scale=preset)
        self._sync(slot)
        self._method, self._options = method, options
        self._interactive = slot
        self._progressive, self._progressive_error = None, None
        self._adapter = _adapter_name(options.get("adapter"))
        if self._display.aov not in aov_names(method):
            self._display = replace(self._display, aov="radiance")
        self._changed()

    def _change_display(self, msg: m.Display) -> None:
        d = self._display
        aov = msg.aov if msg.aov is not None else d.aov
        if aov not in aov_names(self._method):
            raise m.MessageError(
                "aov",
                f"method {self._method!r} has no image {aov!r}"
                f" (use one of: {', '.join(aov_names(self._method))})",
            )
        self._display = DisplayState(
            d.exposure if msg.exposure is None else msg.exposure,
            d.tonemap if msg.tonemap is None else msg.tonemap,
            aov,
        )
        if self._result is not None and _has_image(self._result, aov):
            self._redisplay = True
        else:
            self._changed()

    # Picking and dragging -----------------------------------------------------------------

    def _view(self) -> View:
        camera = self._interactive.renderer.describe("camera")
        return View.of(camera, *self._size)

    def _pick(self, msg: m.Pick, client: int | None) -> dict[str, Any]:
        """Starts a drag of the light or object under (x, y): lights first (they are not
        drawn, so the page marks them), then the nearest object."""
        view = self._view()
        lights = [np.asarray(d["position"], np.float64) for d in self._light_descs]
        found: dict[str, Any] = {"type": "picked", "kind": None}
        light = pick_light(view, lights, msg.x, msg.y)
        if light is not None:
            self._drag = _Drag("light", light, lights[light], lights[light])
            found = {"type": "picked", "kind": "light", "index": light}
        else:
            if self._picker is None:
                vertices, faces = self._scene.mesh_arrays()
                self._picker = ObjectPicker(vertices, faces, self._object_descs)
            matrices = [np.asarray(d["matrix"], np.float64) for d in self._object_descs]
            direction = view.ray(msg.x, msg.y)
            hit = self._picker.pick(view.position, direction, matrices)
            if hit is None:
                self._drag = None
            else:
                i, t = hit
                self._drag = _Drag("object", i, view.position + direction * t, matrices[i])
                name = self._object_descs[i]["name"]
                found = {"type": "picked", "kind": "object", "index": i, "name": name}
        self._on_event(client, found)
        return found

    def _drag_to(self, msg: m.Drag) -> None:
        if self._drag is None:
            raise m.MessageError("drag", "nothing picked (send a pick first)")
        d = self._drag
        point = self._view().drag_point(d.anchor, msg.x, msg.y)
        if point is None:
            return
        offset = point - d.anchor
        if d.kind == "light":
            self._update("light", d.index, {"position": (d.start + offset).tolist()})
        else:
            self._update("object", d.index, {"matrix": translated(d.start, offset)})

    # Frames -------------------------------------------------------------------------------

    def _render(self, slot: _Slot, *, progressive: bool) -> bool:
        """Renders one frame (or pass) with ``slot`` and shows it; ``False`` if it was
        cancelled."""
        with self._cond:
            ops = self._done
            seqs = dict(self._seqs)
        if not progressive:
            self._dirty = False
        d = self._display
        aov = d.aov
        base = set(gi.RenderResult.BASE) - {"radiance"}
        # The beauty of an interactive frame: its 8-bit display image alone (tone-mapped on
        # the GPU by `direct` and `ispm`); a progressive pass keeps the float radiance, so
        # that a display change re-shows the refined image without a new pass.
        display_only = aov == "radiance" and not progressive
        try:
            r = self._sync(slot)
            result = r.render(
                aovs=aov in base or aov == "position",
                extras=aov not in gi.RenderResult.BASE,
                progress=lambda _stage, _f: not self._cancel_requested(progressive),
                radiance=None if display_only else "float32",
                tonemap=d.tonemap if display_only else None,
                exposure=d.exposure,
            )
        except gi.RenderCancelled:
            if not progressive:
                self._dirty = True
            return False
        except gi.GiError as e:
            self._report(None, e)
            return False
        if not progressive:
            # Refinement waits for a still view after the frame, not after the change.
            self._last_change = time.monotonic()
        meta = {
            "progressive": progressive,
            "passes": result.stats.passes if progressive else 0,
            "lights": self._light_marks(),
            "doing": _doing(r, progressive, result.stats.passes),
        }
        self._show(result, meta, ops, seqs)
        return True

    def _renderer(self, method: str, options: dict[str, Any], *, progressive: bool) -> Renderer:
        """A renderer of ``method`` with the options it takes, the rest from its preset
        (:mod:`gi.presets`); ``progressive`` is the viewer's to set."""
        if progressive:
            preset = PROGRESSIVE_PASS.get(method, {})
        else:
            preset = INTERACTIVE.get(method, Interactive()).options
        given = method_options(method, **with_preset(preset, options))
        given.pop("progressive", None)
        if progressive:
            given["progressive"] = True
        return Renderer(self._scene, method, **given)

    def _refine(self) -> None:
        if self._progressive is None:
            if not any(row["name"] == "progressive" for row in options_table(self._method)):
                self._progressive_error = f"method {self._method!r} has no progressive mode"
                self._on_event(None, {**self.state(), "type": "state"})
                return
            try:
                r = self._renderer(self._method, self._options, progressive=True)
            except gi.GiError as e:
                self._progressive_error = str(e)
                self._on_event(None, {**self.state(), "type": "state"})
                return
            self._progressive = _Slot(r)
        self._render(self._progressive, progressive=True)

    def _light_marks(self) -> list[list[float] | None]:
        view = self._view()
        marks: list[list[float] | None] = []
        for d in self._light_descs:
            s = view.project(np.asarray(d["position"], np.float64))
            marks.append(None if s is None else [s[0], s[1]])
        return marks

    def _show(
        self,
        result: RenderResult | None,
        meta: dict[str, Any],
        ops: int | None = None,
        seqs: dict[int, int] | None = None,
    ) -> None:
        """Displays ``result`` (tone map or AOV mapping), encodes it and hands it on."""
        self._redisplay = False
        if result is None:
            return
        self._result, self._result_meta = result, meta
        start = time.perf_counter()
        d = self._display
        if result.display8.size and result.display_settings == (d.tonemap, d.exposure):
            pixels = result.display8
        elif d.aov == "radiance" or not _has_image(result, d.aov):
            pixels = quantize8(to_display(result.radiance, d.tonemap, d.exposure))
        else:
            depth = result.depth if result.depth.size else None
            shown = aov_display(d.aov, result.aov(d.aov), depth, d.tonemap, d.exposure)
            pixels = quantize8(shown)
        png = png_bytes(pixels, compression=1)
        s = result.stats
        h, w = pixels.shape[:2]
        self._frame_id += 1
        frame_meta = {
            **meta,
            "type": "frame",
            "id": self._frame_id,
            "width": w,
            "height": h,
            "method": s.method,
            "aov": d.aov,
            "stages": [[n, t] for n, t in s.stages],
            "total_seconds": s.total_seconds,
            "photons_emitted": s.photons_emitted,
            "photons_stored": s.photons_stored,
            "estimator": s.estimator,
            # Tone mapping and PNG encoding of this frame.
            "encode_seconds": time.perf_counter() - start,
        }
        with self._cond:
            ops = self._done if ops is None else ops
            frame = Frame(
                self._frame_id,
                pixels,
                png,
                frame_meta,
                ops,
                dict(self._seqs) if seqs is None else seqs,
            )
            self._frame = frame
            self._frame_ops = max(self._frame_ops, ops)
            self._cond.notify_all()
        self._on_frame(frame)

    # Reports ------------------------------------------------------------------------------

    def _report(self, client: int | None, error: BaseException) -> None:
        field = getattr(error, "field", None) or getattr(error, "setting", None)
        self._on_event(
            client,
            {"type": "error", "message": str(error), "field": field, "kind": type(error).__name__},
        )

    def _state_locked(self, source: int | None) -> dict[str, Any]:
        camera = self._changes.get(("camera", None), (0, None))[1]
        if camera is None:
            camera = {k: v for k, v in self._scene_camera.items() if k not in ("width", "height")}
        return {
            "source": source,
            "camera": camera,
            "lights": self._light_descs,
            "environment": {
                "source": self._environment.source,
                "strength": self._environment.strength,
                "rotation": self._environment.rotation,
                "mode": self._environment.mode,
                "choices": [*m.ENVIRONMENTS, *self._env_files.choices()],
            },
            "objects": [d["name"] for d in self._object_descs],
            "method": self._method,
            "settings": {k: self._options.get(k) for k in m.SETTINGS if k != "method"},
            "methods": gi.methods(),
            "aovs": aov_names(self._method),
            "tonemaps": list(TONEMAPS),
            "display": {
                "exposure": self._display.exposure,
                "tonemap": self._display.tonemap,
                "aov": self._display.aov,
            },
            "size": list(self._size),
            "paused": self._paused,
            "progressive": {"available": self._progressive_error is None},
            "progressive_error": self._progressive_error,
            "adapter": self._adapter,
            "scene": self._scene.source,
            "pixels": list(self._pixels),
            # The panel's options for this method (option table rows; absent: not taken),
            # the default being what the viewer's interactive frames use.
            "options": {
                row["name"]: {
                    **{k: row.get(k) for k in ("default", "range", "doc", "choices")},
                    **_interactive_default(self._method, row["name"]),
                }
                for row in options_table(self._method)
                if row["name"] in m.SETTINGS
            },
        }


def _interactive_default(method: str, name: str) -> dict[str, Any]:
    """``{"default": value}`` where the viewer's interactive preset sets option ``name``."""
    options = INTERACTIVE.get(method, Interactive()).options
    return {"default": options[name]} if name in options else {}


def _doing(renderer: Renderer, progressive: bool, passes: int) -> str:
    """What made a frame, for the page: the interactive renderer while the view changes,
    the progressive one refining a still view."""
    w, h = renderer.size
    settings = describe(renderer.options)
    each = f" of {settings}" if settings else ""
    if progressive:
        return f"still: refining {w}×{h}, pass {passes}{each}"
    return f"moving: {w}×{h}{f', {settings}' if settings else ''} a frame"


def _update_arguments(target: str, key: Any, value: dict[str, Any]) -> dict[str, Any]:
    """The :meth:`gi.Renderer.update` keywords of one change."""
    if target in ("camera", "environment"):
        return {target: value}
    return {f"{target}s": {key: value}}


def _has_image(result: RenderResult, name: str) -> bool:
    return name in result.aov_names() and result.aov(name).size > 0


def _adapter_name(adapter: str | None) -> str:
    """The GPU adapter's line of :func:`gi.adapter_report` (the CPU methods use none)."""
    try:
        report = gi.adapter_report(adapter)
    except gi.GiError as e:
        return f"adapter: {e}"
    lines = [ln.strip() for ln in report.splitlines() if ln.strip()]
    return lines[0] if lines else ""
