"""Checks of the settings that stay in Python (output exposure, the CLI's footprint
arguments): :class:`gi.SettingError` naming the setting (``.setting``) before any work
starts. The render settings are checked by the native module (``settings_from``) and the
core's ``Settings::validate``.
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


def float_setting(name: str, value: Any) -> float:
    """``value`` as a finite ``float`` (bools, strings, NaN and infinities refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise setting_error(name, f"must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise setting_error(name, f"must be finite, got {v}")
    return v


def exposure_setting(value: Any) -> float:
    """An exposure in stops, finite and within ±:data:`MAX_EXPOSURE`."""
    v = float_setting("exposure", value)
    if abs(v) > MAX_EXPOSURE:
        raise setting_error("exposure", f"{v} stops is outside ±{MAX_EXPOSURE:g}")
    return v
