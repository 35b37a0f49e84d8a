"""The radiance in the form asked for (issue 45 item 3): ``Renderer.render(radiance=...,
tonemap=..., exposure=...)``. The 8-bit image that ``direct`` and ``ispm`` tone-map on the
GPU equals :func:`gi.display.to_srgb8` of the same frame's float radiance within 1 LSB
(the GPU's f32 ``pow``/``log2`` against numpy's: a value on a rounding edge moves by one
step); half floats equal the float radiance within one half-float step (2^-10 relative:
lavapipe's Rgba16Float store rounds toward zero)."""

import numpy as np
import pytest

import gi
from gi.display import to_srgb8

SMALL = {"size": (48, 36), "spp": 4, "photons": 6000, "k": 16, "max_depth": 4}


@pytest.fixture(scope="module")
def cornell() -> gi.Scene:
    return gi.load_scene("cornell")


def _lsb(a: np.ndarray, b: np.ndarray) -> tuple[int, float]:
    """Largest difference of two uint8 images and the share of channels that differ."""
    d = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return int(d.max()), float(np.mean(d > 0))


@pytest.mark.parametrize("method", ["ispm", "direct", "path"])
@pytest.mark.parametrize(("tonemap", "exposure"), [("clip", 1.5), ("filmic", 0.0)])
def test_display_image_equals_the_cpu_tone_map(cornell, method, tonemap, exposure):
    r = gi.Renderer(cornell, method, **gi.method_options(method, **SMALL))
    frame = r.render(tonemap=tonemap, exposure=exposure)
    assert frame.display8.dtype == np.uint8 and frame.display8.shape == (36, 48, 3)
    assert frame.display_settings == (tonemap, exposure)
    largest, share = _lsb(frame.display8, to_srgb8(frame.radiance, exposure, tonemap))
    assert largest <= 1 and share <= 0.01, (largest, share)
    assert frame.display8.max() > 30
    np.testing.assert_array_equal(frame.display(tonemap, exposure), frame.display8)


def test_only_the_display_image_is_read_back(cornell):
    """``radiance=None``: an empty radiance, the display image alone (a still frame, so
    equal to the float frame's tone map within 1 LSB); another display asks for a render."""
    r = gi.Renderer(cornell, "ispm", **SMALL)
    full = r.render()
    only = r.render(radiance=None, tonemap="clip")
    assert only.radiance.size == 0 and only.display8.shape == (36, 48, 3)
    assert _lsb(only.display8, to_srgb8(full.radiance))[0] <= 1
    with pytest.raises(gi.SettingError, match="radiance=None"):
        only.display("filmic")
    assert "radiance" in only.aov_names() and only.aov("radiance").size == 0


def test_half_floats_within_half_precision(cornell):
    r = gi.Renderer(cornell, "ispm", **SMALL)
    full = r.render()
    half = r.render(radiance="float16")
    assert half.radiance.dtype == np.float16 and half.radiance.shape == full.radiance.shape
    f = full.radiance
    tol = np.abs(f) * 2.0**-10 + 6e-8
    assert np.all(np.abs(half.radiance.astype(np.float32) - f) <= tol)
    assert f.max() > 0.01


def test_aces_is_tone_mapped_in_python(cornell):
    """``aces`` (OpenColorIO) is not a core tone map: the float radiance is read back and
    dropped after Python's tone map when not asked for."""
    r = gi.Renderer(cornell, "direct", **gi.method_options("direct", **SMALL))
    frame = r.render(radiance=None, tonemap="aces")
    assert frame.radiance.size == 0 and frame.display8.shape == (36, 48, 3)
    both = r.render(tonemap="aces")
    np.testing.assert_array_equal(frame.display8, to_srgb8(both.radiance, 0.0, "aces"))


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"radiance": "float64"}, "radiance"),
        ({"radiance": 16}, "radiance"),
        ({"tonemap": "reinhard"}, "tonemap"),
        ({"tonemap": "clip", "exposure": float("nan")}, "exposure"),
    ],
)
def test_bad_readouts_are_setting_errors(cornell, kwargs, field):
    r = gi.Renderer(cornell, "direct", **gi.method_options("direct", **SMALL))
    with pytest.raises(gi.SettingError) as e:
        r.render(**kwargs)
    assert field in str(e.value)
