"""Checks of the settings that stay in Python (output paths, formats, exposure, tone
mappers, AOV names, the arguments of :class:`gi.Renderer`'s methods): :class:`gi.SettingError`
naming the setting (``.setting``) and what it allows, before any work starts. The render
settings are checked by the native module (``settings_from``) and the core's
``Settings::validate``.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from gi._gi import GiError, SettingError

U32_MAX = 2**32 - 1
U64_MAX = 2**64 - 1
#: Largest exposure (stops, either sign) that :func:`gi.save_image` accepts: 2^±64 keeps
#: every float32 radiance finite or clips it, and no real image needs more.
MAX_EXPOSURE = 64.0


class SettingValueError(SettingError, ValueError):
    """The :class:`gi.SettingError` of the Python layer's checks. It is also a ``ValueError``:
    what the image-output functions raised before their errors were typed."""


class AovError(SettingValueError, KeyError):
    """An image a :class:`gi.RenderResult` does not hold (``.setting`` is ``aovs``); also a
    ``KeyError``, as :meth:`gi.RenderResult.aov` raised before its errors were typed."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.setting = "aovs"

    __str__ = Exception.__str__


class OutputError(GiError, OSError):
    """An output file cannot be written (a directory in the way, no permission, a full disk,
    a failed encode); ``.path`` names it. Also an ``OSError``. Nothing is left half-written."""

    path: str

    def __init__(self, path: object, reason: str) -> None:
        super().__init__(f"cannot write {path}: {reason}")
        self.path = str(path)


def setting_error(name: str, message: str) -> SettingError:
    """``invalid setting `name`: message`` (``.setting`` = ``name``)."""
    return named_error(name, f"invalid setting `{name}`: {message}")


def named_error(name: str, message: str) -> SettingError:
    """A :class:`gi.SettingError` for setting ``name`` with the whole ``message``."""
    err = SettingValueError(message)
    err.setting = name  # type: ignore[attr-defined]
    return err


def int_setting(name: str, value: Any, maximum: int = U32_MAX) -> int:
    """``value`` as an ``int`` in ``0..=maximum`` (bools and non-integers refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise setting_error(name, f"must be an integer in 0..={maximum}, got {value!r}")
    v = int(value)
    if not 0 <= v <= maximum:
        raise setting_error(name, f"must be in 0..={maximum}, got {v}")
    return v


def float_setting(name: str, value: Any) -> float:
    """``value`` as a finite ``float`` (bools, strings, NaN and infinities refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise setting_error(name, f"must be a finite number, got {value!r}")
    try:
        v = float(value)
    except OverflowError:  # an int beyond float's range
        v = math.inf
    if not math.isfinite(v):
        raise setting_error(name, f"must be a finite number, got {v}")
    return v


def exposure_setting(value: Any) -> float:
    """An exposure in stops, finite and within ±:data:`MAX_EXPOSURE`."""
    v = float_setting("exposure", value)
    if abs(v) > MAX_EXPOSURE:
        raise setting_error("exposure", f"must be in ±{MAX_EXPOSURE:g} stops, got {v}")
    return v
