#!/usr/bin/env python3
"""Writes python/gi/mitsuba/cie_tables.npz: the CIE 1931 2° colour matching functions and the
D65 illuminant as Mitsuba 3 tabulates them (95 samples, 360–830 nm every 5 nm, float32), read
from a Mitsuba 3 source checkout (`src/core/spectrum.cpp`, `include/mitsuba/core/spectrum.h`),
so that gi's spectrum → sRGB conversion (gi.mitsuba.spectra) integrates the very same tables.

    scripts/data/cie_tables.py /path/to/mitsuba3
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[2] / "python/gi/mitsuba/cie_tables.npz"
SAMPLES = 95


def floats(text: str, start: str) -> np.ndarray:
    """The numbers of the C array initializer that follows `start`."""
    body = text[text.index(start) :]
    body = body[body.index("{") + 1 : body.index("};")]
    return np.array(re.findall(r"[-+]?\d+\.\d*(?:[eE][-+]?\d+)?", body), np.float32)


def main() -> None:
    root = Path(sys.argv[1])
    cie = floats((root / "src/core/spectrum.cpp").read_text(), "cie1931_tbl[")
    d65 = floats((root / "include/mitsuba/core/spectrum.h").read_text(), "d65_table[")
    assert cie.shape == (3 * SAMPLES,) and d65.shape == (SAMPLES,), (cie.shape, d65.shape)
    np.savez_compressed(OUT, xyz=cie.reshape(3, SAMPLES), d65=d65)
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
