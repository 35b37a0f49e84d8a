#!/usr/bin/env python3
"""The `path` reference of `cornell` at 128×128 that tests/test_gather_defaults.py compares
`gather`'s default image with (issue 46, item 8): 1024 samples a pixel, seed 7, written as
tests/data/cornell-path-128.exr (its pixel noise, ~0.5% a pixel, is far below what the test
bounds).

    .venv/bin/python scripts/data/gather_reference.py
"""

from __future__ import annotations

from pathlib import Path

import gi

OUT = Path(__file__).resolve().parents[2] / "tests" / "data" / "cornell-path-128.exr"


def main() -> None:
    r = gi.render("cornell", "path", spp=1024, size=(128, 128), seed=7)
    gi.save_image(str(OUT), r.radiance)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
