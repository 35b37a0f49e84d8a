"""Light a scene from outside it: an equirectangular environment image or gi's built-in sky
(with a sun), added to the scene's own light or replacing it.

What ``gi render --env``, ``gi.render(..., environment=)``, ``gi.Renderer(...,
environment=)``, ``Renderer.update(environment=)`` and the viewer's panel take. An
environment is given as

- a file name (``"studio.hdr"``, ``"sky.exr"``: as the scene format's ``environment.file``,
  read through OpenImageIO), a float32 (H, W, 3) radiance array, or ``"sky"``;
- or a dict with that as ``"source"`` and any of ``"strength"`` (scale, default 1),
  ``"rotation"`` (degrees about +y, as the scene format's ``environment.rotation``),
  ``"sun"`` (``"sky"`` only: the direction *towards* the sun, ``[x, y, z]``, default
  :data:`SUN`; ``None`` for a sky without a sun) and ``"mode"``: ``"add"`` (default: the
  scene keeps its lights, and a scene's own environment is summed with this one) or
  ``"replace"`` (the scene's lights and environment are dropped; its emitting surfaces,
  which are materials, stay).

The built-in sky (:func:`sky_image`) is a smooth clear-sky gradient (no physical model: a
backdrop and fill light), 2 W·sr⁻¹·m⁻² at the zenith, brighter towards the horizon and
around the sun's azimuth, a dim ground below the horizon; its sun is a directional light of
:data:`SUN_IRRADIANCE` W/m² and 0.53° (the sun's disc), about 4 times the sky's irradiance
on a horizontal surface, as on a clear day. Both scale with ``strength``; ``rotation``
turns the sky and its sun together.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from gi import _checks
from gi._gi import Scene

#: Default direction towards the built-in sky's sun: 45° up, from +x and +z.
SUN = (0.5, 0.7071, 0.5)
#: The built-in sun's irradiance (W/m² per channel) on a surface facing it, before strength.
SUN_IRRADIANCE = (6.5, 6.2, 5.6)
_SKY_SIZE = (128, 64)
_MODES = ("add", "replace")


def _field_error(field: str, message: str) -> Exception:
    return _checks.setting_error(f"environment.{field}" if field else "environment", message)


def _number(value: Any, field: str, lo: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise _field_error(field, f"must be a number, got {value!r}")
    x = float(value)
    if not math.isfinite(x) or (lo is not None and x < lo):
        raise _field_error(field, f"must be finite{'' if lo is None else ' and ≥ 0'}, got {x}")
    return x


def _direction(value: Any, field: str) -> np.ndarray:
    try:
        d = np.asarray(value, dtype=np.float64).reshape(3)
    except (TypeError, ValueError) as e:
        raise _field_error(field, f"must be [x, y, z], got {value!r}") from e
    n = float(np.linalg.norm(d))
    if not np.isfinite(d).all() or n == 0.0:
        raise _field_error(field, f"must be a finite, non-zero direction, got {value!r}")
    return d / n


def _rotate_y(d: np.ndarray, degrees: float) -> np.ndarray:
    """``d`` turned about +y as the scene format's ``rotation`` turns the sky (+z goes to
    ``(sin r, 0, cos r)``)."""
    r = math.radians(degrees)
    c, s = math.cos(r), math.sin(r)
    return np.array([c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]])


def sky_image(
    sun: np.ndarray | None, width: int = _SKY_SIZE[0], height: int = _SKY_SIZE[1]
) -> np.ndarray:
    """The built-in sky, float32 (height, width, 3), in the sky's own frame (Mitsuba's
    ``envmap`` layout: top row +y, u grows with ``atan2(x, −z)``); ``sun``: the unit
    direction towards the sun in that frame (its azimuth brightens the horizon)."""
    rows = (np.arange(height) + 0.5) / height
    cols = (np.arange(width) + 0.5) / width
    elevation = 90.0 - rows * 180.0
    phi = cols * 2 * math.pi
    zenith = np.array([0.45, 0.75, 1.6])
    horizon = np.array([1.5, 1.6, 1.75])
    ground = np.array([0.3, 0.27, 0.24])

    def smooth(x: np.ndarray) -> np.ndarray:
        x = np.clip(x, 0.0, 1.0)
        return x * x * (3 - 2 * x)

    up = smooth(elevation / 60.0)[:, None, None]
    down = smooth(-elevation / 10.0)[:, None, None]
    img = horizon * (1 - up) + zenith * up
    img = img * (1 - down) + ground * down
    if sun is not None:
        # Mitsuba's layout: column u looks along (sin 2πu, ·, −cos 2πu).
        sun_phi = math.atan2(sun[0], -sun[2])
        glow = 0.5 * np.exp(-2.0 * (1 - np.cos(phi - sun_phi)))[None, :, None]
        img = img * (1 + glow * (1 - up) * (1 - down))
    return np.ascontiguousarray(np.broadcast_to(img, (height, width, 3)), dtype=np.float32)


class Lighting:
    """A parsed ``environment=`` value: the scene format's ``environment`` section, the
    image it names, the lights to add (the sky's sun) and the mode."""

    def __init__(self, value: Any, base_dir: Path | None = None):
        spec = value if isinstance(value, dict) else {"source": value}
        unknown = set(spec) - {"source", "strength", "rotation", "sun", "mode"}
        if unknown:
            raise _field_error(
                sorted(unknown)[0], "unknown (use source, strength, rotation, sun, mode)"
            )
        if "source" not in spec:
            raise _field_error("source", "missing: a file, an (H, W, 3) array or 'sky'")
        source = spec["source"]
        self.strength = _number(spec.get("strength", 1.0), "strength", lo=0.0)
        self.rotation = _number(spec.get("rotation", 0.0), "rotation")
        self.mode = spec.get("mode", "add")
        if self.mode not in _MODES:
            raise _field_error("mode", f"must be 'add' or 'replace', got {self.mode!r}")
        self.lights: list[dict[str, Any]] = []
        if isinstance(source, str) and source == "sky":
            self.name = "sky"
            self.image = self._sky(spec.get("sun", SUN))
        else:
            if "sun" in spec:
                raise _field_error("sun", "is for the built-in sky (source 'sky') only")
            self.name, self.image = self._image(source, base_dir)
        self.section = {
            "file": self.name,
            "intensity": self.strength,
            "rotation": self.rotation,
        }

    def _sky(self, sun: Any) -> np.ndarray:
        if sun is None:
            return sky_image(None)
        towards = _direction(sun, "sun")
        if towards[1] <= 0.0:
            raise _field_error("sun", f"must point above the horizon (y > 0), got {sun!r}")
        # The image is turned by `rotation`; the sun (given in the world) is not.
        local = _rotate_y(towards, -self.rotation)
        self.lights.append(
            {
                "type": "directional",
                "direction": (-towards).tolist(),
                "irradiance": [self.strength * e for e in SUN_IRRADIANCE],
                "angular_diameter": 0.53,
            }
        )
        return sky_image(local)

    @staticmethod
    def _image(source: Any, base_dir: Path | None) -> tuple[str, np.ndarray]:
        from gi.environment import check_environment_array, load_environment_image

        if isinstance(source, np.ndarray):
            return "(array)", check_environment_array(source, "environment", "environment")
        if not isinstance(source, (str, os.PathLike)):
            raise _field_error(
                "source", f"must be a file, an (H, W, 3) array or 'sky', got {source!r}"
            )
        path = Path(source)
        if base_dir is not None and not path.is_absolute():
            path = base_dir / path
        return str(path), load_environment_image(path, "environment", "environment.source")

    def apply(self, scene: Scene) -> Scene:
        """``scene`` (a :class:`gi.Scene`) with this lighting."""
        return scene.with_lighting(**self.native_args(), source="environment")

    def native_args(self) -> dict[str, Any]:
        """The keywords of the core's ``Scene.with_lighting`` / ``Renderer.set_lighting``."""
        return {
            "environment": json.dumps(self.section),
            "images": {self.name: self.image},
            "lights": json.dumps(self.lights),
            "add": self.mode == "add",
        }


def with_environment(scene: Scene, environment: Any) -> Scene:
    """``scene`` lit by ``environment`` (see the module); ``None`` leaves it as it is."""
    if environment is None:
        return scene
    return Lighting(environment).apply(scene)
