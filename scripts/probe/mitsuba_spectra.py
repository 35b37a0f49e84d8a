#!/usr/bin/env python3
"""Spectra as Mitsuba 3's RGB variants read them against gi.mitsuba.spectra: each spectrum
(Mitsuba's own cbox reflectances and emitter, uniform and out-of-gamut ones) given to a
diffuse BSDF's `reflectance` or an area emitter's `radiance`, read back with `mi.traverse`
(`scalar_rgb`), beside gi's conversion; prints the largest relative difference. The values
in tests/test_mitsuba_upgrade.py come from this.

    PYTHONPATH=python .venv/bin/python scripts/probe/mitsuba_spectra.py
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from gi.mitsuba import spectra

ROOT = Path(__file__).resolve().parents[2]
EXTRA = [
    ("reflectance", "0.3"),
    ("radiance", "2.0"),
    ("reflectance", "400:2, 700:2"),
    ("radiance", "450:1, 460:5, 600:0.5"),
]


def mitsuba_rgb(name: str, value: str) -> np.ndarray:
    import mitsuba as mi

    if ":" in value:
        pairs = [tuple(map(float, p.split(":"))) for p in value.split(",")]
        spectrum = {"type": "spectrum", "value": pairs}
    else:
        spectrum = {"type": "spectrum", "value": float(value)}
    if name == "radiance":
        shape = {"type": "sphere", "e": {"type": "area", "radiance": spectrum}}
    else:
        shape = {"type": "sphere", "b": {"type": "diffuse", "reflectance": spectrum}}
    params = mi.traverse(mi.load_dict({"type": "scene", "s": shape}))
    key = next(k for k in params.keys() if k.endswith(f"{name}.value"))
    return np.array(params[key], np.float64).ravel()


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    text = (ROOT / "tests/scenes/third_party/cbox/cbox.xml").read_text()
    cases = re.findall(r'<spectrum name="(\w+)" value="([^"]+)"', text) + EXTRA
    worst = 0.0
    for name, value in cases:
        emitter = name == "radiance"
        ref = mitsuba_rgb(name, value) * np.ones(3)
        if ":" in value:
            got = spectra.pairs_to_srgb(*spectra.parse_pairs(value), emitter, False)
        else:
            got = spectra.uniform_to_srgb(float(value), emitter)
        err = float(np.abs(got - ref).max() / max(np.abs(ref).max(), 1e-9))
        worst = max(worst, err)
        print(f"{name:11s} {value[:32]:32s} mitsuba {np.round(ref, 7)} gi {np.round(got, 7)}")
    print(f"mitsuba {mi.__version__}: largest relative difference {worst:.1e}")


if __name__ == "__main__":
    main()
