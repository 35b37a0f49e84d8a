"""Spectra to linear sRGB as Mitsuba 3's RGB variants convert them (``Properties::
get_texture_impl`` and ``spectrum_list_to_srgb`` in its ``src/core``):

- wavelength:value pairs: the piecewise-linear spectrum integrated against the CIE 1931
  colour matching functions at 1000 wavelengths over 360–830 nm (those outside the given
  range skipped), times the D65 illuminant for reflectances (not for emitters), scaled so
  that a unit spectrum has luminance 1, then XYZ → linear sRGB; reflectances are clamped
  to [0, 1], emitters and unbounded properties (a conductor's ``eta``/``k``) to ≥ 0;
- a single value (a uniform spectrum): that value as grey, except for an emitter, where
  Mitsuba takes ``value · xyz_to_srgb(1, 1, 1)`` (the slightly purple RGB of a flat
  spectrum under sRGB's D65 white), so that RGB variants match spectral ones;
- ``filename``: a text file of ``wavelength value`` lines (``#`` comments), as pairs;
- ``type="blackbody"`` (``temperature`` in K, ``wavelength_min``/``wavelength_max``, 360 and
  830 nm by default): Planck's spectral radiance per nanometre (W·m⁻²·sr⁻¹·nm⁻¹), zero
  outside the range, as Mitsuba's ``blackbody`` plugin evaluates it, converted as pairs
  sampled every 0.5 nm. Mitsuba's RGB variants refuse the plugin at render time ("not
  implemented for non-spectral modes"); its spectral variants integrate it against the
  CIE curves, which the pairs' conversion does (tests/test_mitsuba_spectra_more.py holds
  `scalar_spectral`'s film values).

The CIE tables are Mitsuba's own (``cie_tables.npz``, written by
``scripts/data/cie_tables.py``)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np

CIE_MIN, CIE_MAX, CIE_SAMPLES = 360.0, 830.0, 95
Y_NORMALIZATION = 1.0 / 106.7502593994140625
D65_NORMALIZATION = 1.0 / 98.99741751876255
XYZ_TO_SRGB = np.array(
    [
        [3.240479, -1.537150, -0.498535],
        [-0.969256, 1.875991, 0.041556],
        [0.055648, -0.204043, 1.057311],
    ],
    np.float32,
).astype(np.float64)
STEPS = 1000


@cache
def _tables() -> tuple[np.ndarray, np.ndarray]:
    data = np.load(Path(__file__).with_name("cie_tables.npz"))
    return data["xyz"].astype(np.float64), data["d65"].astype(np.float64)


def _lerp_table(table: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Mitsuba's table lookup: linear between the two samples around `w` (zero outside)."""
    t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) / (CIE_MAX - CIE_MIN))
    i0 = np.clip(t.astype(np.int64), 0, CIE_SAMPLES - 2)
    w1 = t - i0
    v = (1.0 - w1) * table[..., i0] + w1 * table[..., i0 + 1]
    return np.where((w >= CIE_MIN) & (w <= CIE_MAX), v, 0.0)


def pairs_to_srgb(
    wavelengths: np.ndarray, values: np.ndarray, emitter: bool, unbounded: bool
) -> np.ndarray:
    """Mitsuba's ``spectrum_list_to_srgb(wavelengths, values, bounded=not (emitter or
    unbounded), d65=not emitter)`` (wavelengths in nm, increasing)."""
    xyz_table, d65_table = _tables()
    w = CIE_MIN + (np.arange(STEPS) / (STEPS - 1)) * (CIE_MAX - CIE_MIN)
    w = w[(w >= wavelengths[0]) & (w <= wavelengths[-1])]
    # The interval holding each w: the last sample at or below it, at most the one before last.
    idx = np.clip(np.searchsorted(wavelengths, w, side="right") - 1, 0, len(wavelengths) - 2)
    w0, w1 = wavelengths[idx], wavelengths[idx + 1]
    v = ((w - w1) * values[idx] + (w0 - w) * values[idx + 1]) / (w0 - w1)
    if not emitter:
        v = v * _lerp_table(d65_table, w) * D65_NORMALIZATION
    xyz = (_lerp_table(xyz_table, w) * v).sum(axis=1)
    xyz *= (CIE_MAX - CIE_MIN) * Y_NORMALIZATION / STEPS
    rgb = XYZ_TO_SRGB @ xyz
    if not (emitter or unbounded):
        return np.clip(rgb, 0.0, 1.0)
    return np.maximum(rgb, 0.0)


# Planck's law: 2hc², hc/k (SI units).
PLANCK_C1 = 2.0 * 6.62607015e-34 * 299792458.0**2
PLANCK_C2 = 6.62607015e-34 * 299792458.0 / 1.380649e-23


def blackbody_pairs(
    temperature: float, w_min: float = 360.0, w_max: float = 830.0
) -> tuple[np.ndarray, np.ndarray]:
    """Planck's spectral radiance at `temperature` (K) per nm, sampled every 0.5 nm over
    [`w_min`, `w_max`]; ValueError for a temperature ≤ 0 or an empty range."""
    if not (temperature > 0 and np.isfinite(temperature)):
        raise ValueError("the temperature must be positive")
    if not (0 < w_min < w_max and np.isfinite(w_max)):
        raise ValueError("wavelength_min must be below wavelength_max")
    w = np.linspace(w_min, w_max, int(np.ceil((w_max - w_min) * 2)) + 1)
    lam = w * 1e-9
    v = PLANCK_C1 / (lam**5 * np.expm1(PLANCK_C2 / (lam * temperature))) * 1e-9
    return w, v


def uniform_to_srgb(value: float, emitter: bool) -> np.ndarray:
    """A uniform spectrum: grey, or for an emitter ``value · xyz_to_srgb(1, 1, 1)``."""
    if emitter:
        return value * XYZ_TO_SRGB.sum(axis=1)
    return np.full(3, value)


def parse_pairs(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``"400:0.5, 500:0.6"`` → wavelengths, values; ValueError when malformed or when the
    wavelengths do not increase."""
    ws, vs = [], []
    for item in text.replace("\n", ",").split(","):
        if not item.strip():
            continue
        w, v = item.split(":")
        ws.append(float(w))
        vs.append(float(v))
    return _checked(ws, vs)


def read_spd(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A spectrum file: ``wavelength value`` per line, ``#`` starts a comment."""
    ws, vs = [], []
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        w, v = line.split()
        ws.append(float(w))
        vs.append(float(v))
    return _checked(ws, vs)


def _checked(ws: list[float], vs: list[float]) -> tuple[np.ndarray, np.ndarray]:
    w, v = np.array(ws), np.array(vs)
    if len(w) < 2:
        raise ValueError("a sampled spectrum needs at least two wavelengths")
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(v))):
        raise ValueError("values must be finite")
    if np.any(np.diff(w) <= 0):
        raise ValueError("wavelengths must increase")
    return w, v
