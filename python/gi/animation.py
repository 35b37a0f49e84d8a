"""Keyframed animation: a scene's ``animation`` tracks evaluated over time, and sequences of
frames rendered through one :class:`gi.Renderer`.

The tracks are part of the scene format (``docs/scene-format.md``, ``animation``); the core
validates and evaluates them. Frame ``n`` of a sequence shows time ``n / fps`` seconds.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Sequence, Sized
from typing import IO, Any, Protocol

from gi._checks import setting_error
from gi._gi import RenderCancelled, Scene
from gi.result import RenderResult

ProgressCallback = Callable[[str, float], "bool | None"]


class Animated(Protocol):
    """What :func:`render_frames` asks of a renderer (:class:`gi.Renderer`)."""

    def apply_animation(self, time: float) -> None: ...

    def render(self, *, aovs: bool, extras: bool, seed: int | None) -> RenderResult: ...


def animation_updates(scene: Scene, time: float) -> dict[str, Any]:
    """The scene's animated targets at ``time`` (seconds) as keyword arguments of
    :meth:`gi.Renderer.update`: ``{"camera": {...}, "lights": {index: {...}}, "objects":
    {name: transform}, "materials": {name: {...}}}``, each the target's whole description at
    that time. Empty for a scene without an ``animation`` section.

    >>> r.update(**gi.animation_updates(scene, 1.5))     # pose the renderer at t = 1.5 s
    """
    out: dict[str, Any] = {}
    groups = {"light": "lights", "object": "objects", "material": "materials"}
    for u in scene.animation_at(float(time)):
        if u["target"] == "camera":
            out["camera"] = u["value"]
        else:
            out.setdefault(groups[u["target"]], {})[u["key"]] = u["value"]
    return out


#: Most frames one sequence renders (a bound against a mistyped fps or frame range, which
#: would otherwise be checked, and rendered, for ever).
MAX_FRAMES = 1_000_000


def default_frames(scene: Scene, fps: float) -> range:
    """The frames of the whole animation at ``fps``: ``range(round(duration · fps))``."""
    duration = scene.animation_duration
    if duration is None:
        raise setting_error("frames", "the scene has no animation; give the frames to render")
    count = duration * check_fps(fps)
    if not count <= MAX_FRAMES:
        raise setting_error(
            "fps",
            f"{fps:g} fps makes {count:g} frames of the {duration:g} s animation; a sequence"
            f" has at most {MAX_FRAMES}",
        )
    return range(max(1, round(count)))


def check_fps(fps: float) -> float:
    try:
        value = float(fps)
    except (TypeError, ValueError, OverflowError):
        raise setting_error("fps", f"must be a finite number > 0, got {fps!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise setting_error("fps", f"must be a finite number > 0, got {fps!r}")
    return value


def check_frames(frames: Iterable[int]) -> list[int]:
    size = len(frames) if isinstance(frames, Sized) else 0
    if size > MAX_FRAMES:
        raise setting_error("frames", f"{size} frames; a sequence has at most {MAX_FRAMES}")
    out = []
    for n in frames:
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise setting_error("frames", f"frame numbers are integers >= 0, got {n!r}")
        out.append(n)
    if not out:
        raise setting_error("frames", "no frames to render")
    return out


class FrameProgressBar:
    """One line on ``stream`` for a whole sequence: frames done, elapsed and estimated
    remaining time. Writes nothing when ``stream`` is not a terminal (logs stay clean)."""

    def __init__(self, total: int, stream: IO[str] | None = None, width: int = 30) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.total = total
        self.width = width
        self.start = time.monotonic()
        isatty = getattr(self.stream, "isatty", None)
        self.enabled = bool(isatty and isatty())

    def __call__(self, done: int) -> None:
        if not self.enabled:
            return
        fraction = done / self.total
        filled = int(self.width * fraction)
        bar = "#" * filled + "-" * (self.width - filled)
        elapsed = time.monotonic() - self.start
        eta = elapsed / done * (self.total - done) if done else 0.0
        end = "\n" if done >= self.total else ""
        self.stream.write(
            f"\r  frames [{bar}] {done}/{self.total} {fraction * 100:5.1f}%"
            f" {elapsed:6.1f}s, {eta:6.1f}s left{end}"
        )
        self.stream.flush()


def _frame_progress(progress: bool | ProgressCallback, total: int) -> Callable[[int], None] | None:
    if progress is False:
        return None
    if progress is True:
        return FrameProgressBar(total)
    callback = progress

    def report(done: int) -> None:
        if callback("frames", done / total) is False:
            raise RenderCancelled("render cancelled")

    return report


def render_frames(
    renderer: Animated,
    scene: Scene,
    frames: Iterable[int] | None,
    fps: float,
    *,
    aovs: bool,
    extras: bool,
    seed: int | None,
    progress: bool | ProgressCallback,
) -> Iterator[tuple[int, RenderResult]]:
    """Validates the arguments now, then returns the iterator over the frames."""
    fps = check_fps(fps)
    numbers: Sequence[int] = check_frames(default_frames(scene, fps) if frames is None else frames)
    report = _frame_progress(progress, len(numbers))

    def run() -> Iterator[tuple[int, RenderResult]]:
        if report is not None:
            report(0)
        for done, n in enumerate(numbers, 1):
            renderer.apply_animation(n / fps)
            result = renderer.render(aovs=aovs, extras=extras, seed=seed)
            if report is not None:
                report(done)
            yield n, result

    return run()
