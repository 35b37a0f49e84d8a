"""Progress display for ``gi.render(progress=True)`` and the CLI, through tqdm.

One bar per render stage. In a terminal it is tqdm's text bar on stderr; in a Jupyter
notebook it is tqdm's notebook widget when ipywidgets is installed, else the text bar
(which Jupyter redraws in place); anywhere else, a log file or a pipe, it writes nothing,
so logs get no ``\\r`` frames.
"""

from __future__ import annotations

import shutil
import sys
from typing import IO, Any


def in_notebook() -> bool:
    """Whether this runs inside a Jupyter kernel (IPython's ZMQ shell)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()  # type: ignore[attr-defined]
    except AttributeError:
        return False
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


def interactive(stream: IO[str] | None = None) -> bool:
    """Whether progress would be seen: ``stream`` (stderr) is a terminal, or a notebook."""
    stream = stream or sys.stderr
    try:
        tty = stream.isatty()
    except (AttributeError, ValueError):
        tty = False
    return bool(tty) or in_notebook()


def _has_ipywidgets() -> bool:
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        return False
    return True


class ProgressBar:
    """A ``(stage, fraction) -> bool`` progress callback that draws tqdm bars.

    ``enabled=None`` (auto) draws only where someone sees it (:func:`interactive`);
    ``True`` always draws (text bars on ``stream``), ``False`` never.
    """

    def __init__(self, stream: IO[str] | None = None, enabled: bool | None = None) -> None:
        self.stream = stream or sys.stderr
        self.enabled = interactive(self.stream) if enabled is None else enabled
        self.widgets = self.enabled and in_notebook() and _has_ipywidgets()
        self.stage: str | None = None
        self.bar: Any = None

    def _open(self, stage: str) -> None:
        if self.widgets:
            from tqdm.notebook import tqdm
        else:
            from tqdm import tqdm
        self.bar = tqdm(
            total=100,
            desc=f"{stage:>14}",
            file=None if self.widgets else self.stream,
            bar_format="{desc} {percentage:5.1f}%|{bar}| {elapsed}<{remaining}",
            # Each stage's bar is replaced by the next one: one line on a terminal.
            leave=False,
            ncols=None if self.widgets else min(shutil.get_terminal_size().columns, 100),
        )
        self.stage = stage

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        self.bar, self.stage = None, None

    def __call__(self, stage: str, fraction: float) -> bool:
        if not self.enabled:
            return True
        if stage != self.stage:
            self.close()
            self._open(stage)
        pct = 100.0 * min(max(fraction, 0.0), 1.0)
        self.bar.n = pct
        self.bar.refresh()
        if fraction >= 1.0:
            self.close()
        return True
