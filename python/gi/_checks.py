"""Type and representability checks of settings at the Python boundary.

The native module takes fixed-width integers and floats; a Python ``int`` of any size, a
NaN or a string would otherwise fail inside the binding with an ``OverflowError`` or
``TypeError`` that names no setting. These checks raise :class:`gi.SettingError` with the
setting's name (``.setting``) before any work starts; the ranges that mean something
(``spp`` in 1..=2²⁰, ...) are checked by the core's ``Settings::validate``.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from gi._gi import SettingError

U32_MAX = 2**32 - 1
U64_MAX = 2**64 - 1
#: Largest exposure (stops, either sign) that :func:`gi.save_image` accepts: 2^±64 keeps
#: every float32 radiance finite or clips it, and no real image needs more.
MAX_EXPOSURE = 64.0


def setting_error(name: str, message: str) -> SettingError:
    err = SettingError(f"invalid setting `{name}`: {message}")
    err.setting = name  # type: ignore[attr-defined]
    return err


def int_setting(name: str, value: Any, maximum: int = U32_MAX) -> int:
    """``value`` as an ``int`` in ``0..=maximum`` (bools and non-integers refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise setting_error(name, f"must be an integer, got {value!r}")
    v = int(value)
    if not 0 <= v <= maximum:
        raise setting_error(name, f"{v} is out of range (0..={maximum})")
    return v


def optional_int(name: str, value: Any, maximum: int = U32_MAX) -> int | None:
    return None if value is None else int_setting(name, value, maximum)


def float_setting(name: str, value: Any) -> float:
    """``value`` as a finite ``float`` (bools, strings, NaN and infinities refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise setting_error(name, f"must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise setting_error(name, f"must be finite, got {v}")
    return v


def optional_float(name: str, value: Any) -> float | None:
    return None if value is None else float_setting(name, value)


def str_setting(name: str, value: Any, optional: bool = False) -> str | None:
    if value is None and optional:
        return None
    if not isinstance(value, str):
        raise setting_error(name, f"must be a string, got {value!r}")
    return value


def bool_setting(name: str, value: Any) -> bool:
    if not isinstance(value, (bool, numbers.Integral)) or value not in (0, 1):
        raise setting_error(name, f"must be True or False, got {value!r}")
    return bool(value)


def size_setting(value: Any) -> tuple[int | None, int | None]:
    """``(width, height)`` from ``size`` (``None``: the scene camera's)."""
    if value is None:
        return None, None
    try:
        w, h = value
    except (TypeError, ValueError):
        raise setting_error("size", f"must be (width, height), got {value!r}") from None
    return int_setting("width", w), int_setting("height", h)


def exposure_setting(value: Any) -> float:
    """An exposure in stops, finite and within ±:data:`MAX_EXPOSURE`."""
    v = float_setting("exposure", value)
    if abs(v) > MAX_EXPOSURE:
        raise setting_error("exposure", f"{v} stops is outside ±{MAX_EXPOSURE:g}")
    return v
