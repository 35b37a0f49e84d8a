"""The messages the viewer's page (and scripts, through the HTTP routes) send, checked
before anything acts on them.

Each message is a JSON object with a ``type``; :func:`parse` returns it as one of the
dataclasses below or raises :class:`MessageError` naming the field (``"camera.position[1]"``)
and what is wrong, like :class:`gi.SceneError` does for scene files. Unknown fields are
refused, numbers must be finite, vectors have three of them and sizes are bounded. The scene
values themselves (a light's fields, a transform, a material) are checked by the renderer's
``update``, which refuses what the scene format refuses.
"""

from __future__ import annotations

import json
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gi._checks import MAX_EXPOSURE
from gi._gi import GiError
from gi.display import TONEMAPS
from gi.render import options_table

#: Longest message accepted (bytes of JSON).
MAX_MESSAGE_BYTES = 64 * 1024
#: Largest image side the page may ask for.
MAX_SIDE = 4096
#: Largest coordinate accepted in a camera, light or transform (metres).
MAX_COORDINATE = 1e7


class MessageError(GiError):
    """A message from the page or an HTTP request that is not valid: ``field`` names the
    part (``"camera.position"``) and ``reason`` what is wrong with it."""

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}" if field else reason)
        self.field = field
        self.reason = reason


# The messages -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Camera:
    """Fields of the camera in the scene format (position, look_at, up, fov)."""

    camera: dict[str, Any]
    seq: int | None = None


@dataclass(frozen=True)
class Lights:
    """Light index → fields that change (position, intensity, direction, ...)."""

    lights: dict[int, dict[str, Any]]
    seq: int | None = None


@dataclass(frozen=True)
class Objects:
    """Object index or name → its whole transform (translate/rotate/scale or matrix)."""

    objects: dict[int | str, dict[str, Any]]
    seq: int | None = None


@dataclass(frozen=True)
class Materials:
    """Material name → fields that change."""

    materials: dict[str, dict[str, Any]]
    seq: int | None = None


#: The panel's environment choices: the scene's own light (as loaded, with ``--env`` if
#: given), or the built-in sky with or without its sun (:mod:`gi.lighting`); and an image
#: of the viewer's environment folder, ``FILE_PREFIX + NAME`` (:mod:`gi.viewer.environments`).
ENVIRONMENTS = ("scene", "sky", "sky without sun")
FILE_PREFIX = "file: "


@dataclass(frozen=True)
class Environment:
    """The environment light chosen in the panel (one of :data:`ENVIRONMENTS`), its
    strength, rotation (degrees about +y) and mode ("add" to the scene's light or
    "replace" it)."""

    source: str
    strength: float = 1.0
    rotation: float = 0.0
    mode: str = "add"
    seq: int | None = None

    def spec(self, file: Callable[[str], str] | None = None) -> Any:
        """What :meth:`gi.Renderer.update` takes as ``environment``; ``file`` gives the
        path of a file choice (it raises :class:`MessageError` for one not offered)."""
        if self.source == "scene":
            return "none"
        source = "sky"
        if self.source.startswith(FILE_PREFIX):
            if file is None:
                raise MessageError("source", "this viewer offers no environment files")
            source = file(self.source)
        spec: dict[str, Any] = {
            "source": source,
            "strength": self.strength,
            "rotation": self.rotation,
            "mode": self.mode,
        }
        if self.source == "sky without sun":
            spec["sun"] = None
        return spec


@dataclass(frozen=True)
class Settings:
    """Render options that need a new renderer: method, estimator, photons, subsample
    (``None``: the renderer's default)."""

    settings: dict[str, Any]


@dataclass(frozen=True)
class Display:
    """How frames are shown: exposure (stops), tone map and the image shown (an AOV name,
    ``"radiance"`` for the beauty). ``None`` fields stay as they are."""

    exposure: float | None = None
    tonemap: str | None = None
    aov: str | None = None


@dataclass(frozen=True)
class Resize:
    width: int
    height: int


@dataclass(frozen=True)
class Pause:
    paused: bool


@dataclass(frozen=True)
class Pick:
    """Start dragging the light or object under image position (x, y), each in [0, 1]
    from the top-left corner."""

    x: float
    y: float


@dataclass(frozen=True)
class Drag:
    """Move the picked light or object under image position (x, y)."""

    x: float
    y: float
    seq: int | None = None


@dataclass(frozen=True)
class Drop:
    """End a drag."""


@dataclass(frozen=True)
class ResetView:
    """The scene file's camera again."""

    seq: int | None = None


@dataclass(frozen=True)
class Ack:
    """The page has drawn frame ``frame``: the server may send the next."""

    frame: int


Message = (
    Camera
    | Lights
    | Objects
    | Materials
    | Environment
    | Settings
    | Display
    | Resize
    | Pause
    | Pick
    | Drag
    | Drop
    | ResetView
    | Ack
)

# Field checks -------------------------------------------------------------------------------


def _obj(value: Any, field: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise MessageError(field, f"expected an object, got {_kind(value)}")
    return value


def _only(obj: dict[str, Any], field: str, allowed: tuple[str, ...]) -> None:
    for key in obj:
        if key not in allowed:
            where = f"{field}.{key}" if field else key
            raise MessageError(where, f"unknown field (expected one of: {', '.join(allowed)})")


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    return {bool: "a boolean", str: "a string", list: "a list", dict: "an object"}.get(
        type(value), "a number" if isinstance(value, numbers.Real) else type(value).__name__
    )


def _number(value: Any, field: str, lo: float = -math.inf, hi: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise MessageError(field, f"expected a number, got {_kind(value)}")
    v = float(value)
    if not math.isfinite(v):
        raise MessageError(field, "must be finite")
    if not lo <= v <= hi:
        raise MessageError(field, f"{v:g} is outside {lo:g}..{hi:g}")
    return v


def _integer(value: Any, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise MessageError(field, f"expected an integer, got {_kind(value)}")
    return int(value)


def _int(value: Any, field: str, lo: int, hi: int) -> int:
    v = _integer(value, field)
    if not lo <= v <= hi:
        raise MessageError(field, f"{v} is outside {lo}..{hi}")
    return v


def _string(value: Any, field: str, choices: tuple[str, ...] | list[str] | None = None) -> str:
    if not isinstance(value, str):
        raise MessageError(field, f"expected a string, got {_kind(value)}")
    if choices is not None and value not in choices:
        raise MessageError(field, f"unknown {value!r} (use one of: {', '.join(choices)})")
    if not 0 < len(value) <= 200:
        raise MessageError(field, "must have 1 to 200 characters")
    return value


def _environment_source(value: Any) -> str:
    """One of :data:`ENVIRONMENTS` or a file choice (``FILE_PREFIX + NAME``: whether the
    viewer offers it is the engine's to check)."""
    source = _string(value, "source")
    if source not in ENVIRONMENTS and not source.startswith(FILE_PREFIX):
        use = ", ".join([*ENVIRONMENTS, FILE_PREFIX + "NAME"])
        raise MessageError("source", f"unknown {source!r} (use one of: {use})")
    return source


def _scene_value(value: Any, field: str, depth: int = 0) -> Any:
    """A scene-format value: finite numbers, strings, booleans, and lists and objects of
    them (at most 4 deep); what the fields mean is the renderer's to check."""
    if depth > 4:
        raise MessageError(field, "nested too deeply")
    if isinstance(value, bool) or isinstance(value, str):
        return value
    if isinstance(value, numbers.Real):
        return _number(value, field, -MAX_COORDINATE, MAX_COORDINATE)
    if isinstance(value, list):
        if len(value) > 16:
            raise MessageError(field, "list too long")
        return [_scene_value(v, f"{field}[{i}]", depth + 1) for i, v in enumerate(value)]
    if isinstance(value, dict):
        return {
            _string(k, field): _scene_value(v, f"{field}.{k}", depth + 1) for k, v in value.items()
        }
    raise MessageError(field, f"expected a number, string, list or object, got {_kind(value)}")


def _fields(value: Any, field: str) -> dict[str, Any]:
    """An object of scene-format fields (a light's, a material's, a transform)."""
    obj = _obj(value, field)
    if not obj:
        raise MessageError(field, "no fields given")
    return _scene_value(obj, field)  # type: ignore[no-any-return]


def _vec3(value: Any, field: str) -> list[float]:
    if not isinstance(value, list) or len(value) != 3:
        raise MessageError(field, f"expected 3 numbers, got {_kind(value)}")
    return [
        _number(v, f"{field}[{i}]", -MAX_COORDINATE, MAX_COORDINATE) for i, v in enumerate(value)
    ]


def _seq(obj: dict[str, Any]) -> int | None:
    return None if obj.get("seq") is None else _int(obj["seq"], "seq", 0, 2**53)


def camera_fields(value: Any, field: str = "camera") -> dict[str, Any]:
    """The camera fields a viewer may change: position, look_at, up (3 numbers each) and
    fov (degrees, in (0, 180)); position and look_at must differ."""
    obj = _obj(value, field)
    _only(obj, field, ("position", "look_at", "up", "fov"))
    if not obj:
        raise MessageError(field, "no fields given")
    out: dict[str, Any] = {}
    for name in ("position", "look_at", "up"):
        if name in obj:
            out[name] = _vec3(obj[name], f"{field}.{name}")
    if "up" in out and math.hypot(*out["up"]) == 0.0:
        raise MessageError(f"{field}.up", "must not be zero")
    if "fov" in obj:
        fov = _number(obj["fov"], f"{field}.fov", 0.0, 180.0)
        if fov in (0.0, 180.0):
            raise MessageError(f"{field}.fov", "must be strictly between 0 and 180 degrees")
        out["fov"] = fov
    if "position" in out and "look_at" in out and out["position"] == out["look_at"]:
        raise MessageError(field, "position and look_at are the same point")
    return out


def lights(value: Any, field: str = "lights") -> dict[int, dict[str, Any]]:
    """``{index: fields}``; JSON object keys are strings, so ``"0"`` means light 0."""
    obj = _obj(value, field)
    if not obj:
        raise MessageError(field, "no lights given")
    out: dict[int, dict[str, Any]] = {}
    for key, fields in obj.items():
        if not (isinstance(key, str) and key.isdigit() and len(key) < 10):
            raise MessageError(f"{field}.{key}", "a light is named by its index")
        out[int(key)] = _fields(fields, f"{field}.{key}")
    return out


def objects(value: Any, field: str = "objects") -> dict[int | str, dict[str, Any]]:
    """``{index or name: transform}``."""
    obj = _obj(value, field)
    if not obj:
        raise MessageError(field, "no objects given")
    out: dict[int | str, dict[str, Any]] = {}
    for key, transform in obj.items():
        name = _string(key, field)
        out[int(name) if name.isdigit() and len(name) < 10 else name] = _fields(
            transform, f"{field}.{key}"
        )
    return out


def materials(value: Any, field: str = "materials") -> dict[str, dict[str, Any]]:
    obj = _obj(value, field)
    if not obj:
        raise MessageError(field, "no materials given")
    return {_string(k, field): _fields(v, f"{field}.{k}") for k, v in obj.items()}


#: The render options the side panel changes (their values are checked against the core's
#: option table, :func:`gi.options_table`).
SETTINGS = ("method", "estimator", "photons", "subsample")


def _option(name: str, value: Any, field: str) -> Any:
    """``value`` if some row of the option table for ``name`` takes it (its choices or
    min..max), whatever the current method: the panel keeps options for other methods."""
    rows = [row for row in options_table() if row["name"] == name]
    for row in rows:
        if "choices" in row and value not in row["choices"]:
            continue
        if "min" in row and not row["min"] <= value <= row["max"]:
            continue
        return value
    raise MessageError(field, f"{value!r} is not {rows[0]['range'] if rows else 'an option'}")


def settings(value: Any, methods: list[str], field: str = "settings") -> dict[str, Any]:
    """Method (one of ``methods``), estimator, photons and subsample (checked against the
    option table); ``null`` goes back to the renderer's default."""
    obj = _obj(value, field)
    _only(obj, field, SETTINGS)
    if not obj:
        raise MessageError(field, "no settings given")
    out: dict[str, Any] = {}
    for key, v in obj.items():
        where = f"{field}.{key}"
        if v is None:
            if key == "method":
                raise MessageError(where, "a method is needed")
            out[key] = None
        elif key == "method":
            out[key] = _string(v, where, methods)
        elif key == "estimator":
            out[key] = _option(key, _string(v, where), where)
        else:
            # The option table's range, not a wider one: "-5 is not an integer in 1..=…".
            out[key] = _option(key, _integer(v, where), where)
    return out


# Parsing ------------------------------------------------------------------------------------


def decode(text: str | bytes) -> dict[str, Any]:
    """JSON text → its top-level object."""
    if len(text) > MAX_MESSAGE_BYTES:
        raise MessageError("", f"message longer than {MAX_MESSAGE_BYTES} bytes")
    try:
        value = json.loads(text)
    except (ValueError, UnicodeDecodeError) as e:
        raise MessageError("", f"not JSON: {e}") from None
    return _obj(value, "message")


def parse(text: str | bytes, methods: list[str]) -> Message:
    """A page message (JSON text) as its dataclass; :class:`MessageError` if invalid."""
    obj = decode(text)
    kind = obj.get("type")
    fields = {
        "camera": ("camera", "seq"),
        "lights": ("lights", "seq"),
        "objects": ("objects", "seq"),
        "materials": ("materials", "seq"),
        "environment": ("source", "strength", "rotation", "mode", "seq"),
        "settings": ("settings",),
        "display": ("exposure", "tonemap", "aov"),
        "resize": ("width", "height"),
        "pause": ("paused",),
        "pick": ("x", "y"),
        "drag": ("x", "y", "seq"),
        "drop": (),
        "reset_view": ("seq",),
        "ack": ("frame",),
    }
    if kind not in fields:
        raise MessageError(
            "type", f"unknown message type {kind!r} (use one of: {', '.join(fields)})"
        )
    _only(obj, "", ("type", *fields[kind]))
    for name in fields[kind]:
        optional = ("seq", "exposure", "tonemap", "aov", "strength", "rotation", "mode")
        if name not in obj and name not in optional:
            raise MessageError(name, "missing")
    if kind == "camera":
        return Camera(camera_fields(obj["camera"]), _seq(obj))
    if kind == "lights":
        return Lights(lights(obj["lights"]), _seq(obj))
    if kind == "objects":
        return Objects(objects(obj["objects"]), _seq(obj))
    if kind == "materials":
        return Materials(materials(obj["materials"]), _seq(obj))
    if kind == "environment":
        return Environment(
            _environment_source(obj["source"]),
            _number(obj.get("strength", 1.0), "strength", 0.0, 1e6),
            _number(obj.get("rotation", 0.0), "rotation", -1e6, 1e6),
            _string(obj.get("mode", "add"), "mode", ("add", "replace")),
            _seq(obj),
        )
    if kind == "settings":
        return Settings(settings(obj["settings"], methods))
    if kind == "display":
        return display(obj)
    if kind == "resize":
        return Resize(
            _int(obj["width"], "width", 1, MAX_SIDE), _int(obj["height"], "height", 1, MAX_SIDE)
        )
    if kind == "pause":
        if not isinstance(obj["paused"], bool):
            raise MessageError("paused", f"expected a boolean, got {_kind(obj['paused'])}")
        return Pause(obj["paused"])
    if kind in ("pick", "drag"):
        x, y = _number(obj["x"], "x", 0.0, 1.0), _number(obj["y"], "y", 0.0, 1.0)
        return Pick(x, y) if kind == "pick" else Drag(x, y, _seq(obj))
    if kind == "drop":
        return Drop()
    if kind == "reset_view":
        return ResetView(_seq(obj))
    return Ack(_int(obj["frame"], "frame", 0, 2**53))


def display(obj: dict[str, Any]) -> Display:
    """The display fields of ``obj`` (exposure, tonemap, aov; each optional)."""
    exposure = obj.get("exposure")
    tonemap = obj.get("tonemap")
    aov = obj.get("aov")
    return Display(
        None if exposure is None else _number(exposure, "exposure", -MAX_EXPOSURE, MAX_EXPOSURE),
        None if tonemap is None else _string(tonemap, "tonemap", TONEMAPS),
        None if aov is None else _string(aov, "aov"),
    )
