"""What the scripts under ``bench/``, ``probe/`` and ``data/`` share: the repository's root,
the machine's CPU name for their tables, and the image error measures (``flip`` from
``tests/image_metrics.py``, the one FLIP the tests and the tables use; ``relmse``).

A script puts this folder on its path and imports from here::

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from shared import ROOT, cpu_name, flip, relmse  # noqa: E402
"""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
"""The repository's root."""

sys.path.insert(0, str(ROOT / "tests"))
from image_metrics import flip  # noqa: E402

__all__ = ["ROOT", "cpu_name", "flip", "relmse"]


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else the machine's architecture."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.machine()


def relmse(x: np.ndarray, ref: np.ndarray) -> float:
    """Relative mean squared error of ``x`` against ``ref`` (1e-2 added to ``ref²``)."""
    return float(np.mean((x - ref) ** 2 / (ref**2 + 1e-2)))
