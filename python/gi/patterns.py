"""Frame-number patterns of output file names, one syntax for ``gi render`` and batch jobs:
printf's ``%d``/``%04d`` (``%%`` is a literal ``%``) and Python's ``{frame}``/``{frame:04d}``
(as in batch jobs' other fields, ``{index}``, ``{scene}`` …), either of them, once."""

from __future__ import annotations

import re

from gi._checks import SettingError, named_error

#: printf conversions (``%04d``, ``%%``, or a lone ``%``) and ``{frame}``/``{frame:04d}``.
_PATTERN = re.compile(r"%(%|\d*d)?|\{frame(?::(\d*d))?\}")


def frame_number_count(path: str) -> int:
    """How many frame numbers ``path`` holds; a ``%`` that is none (nor ``%%``) is an
    error."""
    count = 0
    for m in _PATTERN.finditer(path):
        if m.group(0).startswith("%"):
            if m.group(1) is None:
                raise pattern_error(
                    path, "a frame number is %d or %04d, or {frame:04d} (%% for a %)"
                )
            count += m.group(1) != "%"
        else:
            count += 1
    return count


def frame_path(path: str, frame: int) -> str:
    """``path`` with its frame number (if any) written as ``frame``; ``%%`` becomes ``%``."""

    def one(m: re.Match[str]) -> str:
        text = m.group(0)
        if text == "%%":
            return "%"
        if text.startswith("%"):
            return text % frame
        return format(frame, m.group(2) or "d")

    return _PATTERN.sub(one, path)


def pattern_error(path: str, reason: str) -> SettingError:
    return named_error("output", f"output {path!r}: {reason}")
