"""The environment images the viewer's Environment panel offers: the ``.hdr`` and ``.exr``
files of one folder (``gi view --env-dir DIR``, ``gi.view(env_dir=DIR)``; by default the
folder of ``--env FILE``), listed when the viewer starts.

The page names a file by its choice, ``"file: NAME"``; only the listed names are accepted,
so a page cannot make the server read any other path."""

from __future__ import annotations

from pathlib import Path

import gi
from gi.viewer.messages import FILE_PREFIX, MessageError

#: Image files the environment light reads (equirectangular HDR: :mod:`gi.lighting`).
SUFFIXES = (".hdr", ".exr")


class EnvironmentFiles:
    """The environment images in ``folder`` (``None``: none)."""

    def __init__(self, folder: str | Path | None) -> None:
        self.folder = None if folder is None else Path(folder)
        self.names: list[str] = []
        if self.folder is None:
            return
        if not self.folder.is_dir():
            raise gi.SettingError(f"env_dir: {str(self.folder)!r} is not a folder")
        self.names = sorted(
            p.name
            for p in self.folder.iterdir()
            if p.suffix.lower() in SUFFIXES and p.is_file() and len(p.name) <= 190
        )

    def choices(self) -> list[str]:
        """The panel's choices for the files, ``"file: NAME"`` each."""
        return [FILE_PREFIX + n for n in self.names]

    def path(self, choice: str) -> str:
        """The file of a choice; :class:`MessageError` (field ``source``) for a name that is
        not listed."""
        name = choice.removeprefix(FILE_PREFIX)
        if self.folder is None or name not in self.names:
            listed = ", ".join(self.names) or "none: start the viewer with --env-dir DIR"
            raise MessageError("source", f"no environment file {name!r} (listed: {listed})")
        return str(self.folder / name)
