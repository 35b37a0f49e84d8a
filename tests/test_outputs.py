"""Results the way tools read them: multichannel EXR, visible AOV PNGs, repr and PNG repr."""

import os

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)
import pytest

import gi
from gi import aovs, display, io


@pytest.fixture(scope="module")
def ispm_result():
    # ispm has the most AOVs (its own direct/specular/indirect/photons); tiny on lavapipe.
    return gi.render(
        gi.load_scene("cornell"), "ispm", spp=1, size=(40, 32), photons=4000, adapter="cpu"
    )


def test_exr_holds_beauty_and_named_aov_layers_equal_to_the_arrays(tmp_path, ispm_result):
    r = ispm_result
    out = tmp_path / "frame.exr"
    wanted = ["albedo", "normal", "position", "depth", "direct", "indirect"]
    assert gi.save_result(out, r, wanted) == [out]
    assert sorted(os.listdir(tmp_path)) == ["frame.exr"]  # one file, no temporary left

    buf = oiio.ImageBuf(str(out))
    spec = buf.spec()
    names = list(spec.channelnames)
    expected = {
        "radiance": ["R", "G", "B"],
        "albedo": ["albedo.R", "albedo.G", "albedo.B"],
        "normal": ["N.X", "N.Y", "N.Z"],
        "position": ["P.X", "P.Y", "P.Z"],
        "depth": ["Z"],
        "direct": ["direct.R", "direct.G", "direct.B"],
        "indirect": ["indirect.R", "indirect.G", "indirect.B"],
    }
    assert sorted(names) == sorted(sum(expected.values(), []))
    assert spec.format == oiio.FLOAT and (spec.width, spec.height) == (40, 32)
    assert spec.getattribute("gi:method") == "ispm"
    # Float EXR stores float32 exactly: values equal the arrays gi.render returned.
    pixels = buf.get_pixels(oiio.FLOAT)
    for aov, channels in expected.items():
        got = np.stack([pixels[:, :, names.index(c)] for c in channels], axis=-1)
        want = r.aov(aov)
        assert np.array_equal(got, want if want.ndim == 3 else want[:, :, None]), aov
    # The beauty's channels are what other tools open as "the image".
    assert np.array_equal(gi.read_channels(out)["R"], r.radiance[:, :, 0])


def test_png_aovs_are_mapped_to_a_visible_range(tmp_path, ispm_result):
    r = ispm_result
    files = gi.save_result(tmp_path / "f.png", r, ["normal", "depth", "albedo", "position"])
    assert [f.name for f in files] == [
        "f.png",
        "f.normal.png",
        "f.depth.png",
        "f.albedo.png",
        "f.position.png",
    ]
    hit = r.depth > 0
    normal = gi.read_image(tmp_path / "f.normal.png")
    # n/2 + 1/2 per component, within 8-bit rounding: negative components are not clipped.
    assert np.allclose(normal, r.normal * 0.5 + 0.5, atol=0.5 / 255 + 1e-6)
    assert (r.normal[hit] < -0.5).any()
    depth = gi.read_image(tmp_path / "f.depth.png")[:, :, 0]
    # Before: a PNG of depth was all 1.0. Now nearest white, farthest 15 % grey, misses black.
    assert depth[hit].max() == 1.0 and depth[hit].min() == pytest.approx(0.15, abs=1 / 255)
    assert (depth[~hit] == 0).all() and len(np.unique(depth[hit])) > 20
    near = np.unravel_index(np.argmin(np.where(hit, r.depth, np.inf)), r.depth.shape)
    assert depth[near] == 1.0
    position = gi.read_image(tmp_path / "f.position.png")
    assert position[hit].min() == 0.0 and position[hit].max() == 1.0
    # ispm's photon visualisation: scaled to its 99th percentile, not washed out to white.
    gi.save_result(tmp_path / "p.png", r, ["photons"])
    photons = gi.read_image(tmp_path / "p.photons.png")
    assert np.mean(photons == 1.0) < 0.05 and photons.max() == 1.0
    assert np.array_equal(photons > 0, r.aov("photons") > 0)  # every photon stays visible


def test_outputs_formats_and_aov_names_are_checked_before_rendering(tmp_path):
    with pytest.raises(ValueError, match="method 'path' has no AOV 'indirect'"):
        aovs.check_aovs("path", ["albedo", "indirect"])
    with pytest.raises(ValueError, match="unsupported image format '.xyz'"):
        io.check_output_path(tmp_path / "a.xyz")
    (tmp_path / "d.exr").mkdir()
    with pytest.raises(OSError, match="is a directory"):
        io.check_output_path(tmp_path / "d.exr")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OSError, match="not a directory"):
        io.check_output_path(blocker / "sub" / "a.exr")
    # A path in a directory yet to be created is fine (save_image creates it).
    assert io.check_output_path(tmp_path / "new" / "a.exr").name == "a.exr"


def test_each_methods_aov_names_are_known_before_rendering():
    # gi.aovs declares per method what a render returns so the CLI can check --aov names
    # up front; this keeps the declaration equal to what the renderer really returns.
    scene = gi.load_scene("cornell")
    for method in gi.methods():
        options = gi.method_options(method, spp=1, size=(8, 8), photons=2000, adapter="cpu")
        r = gi.render(scene, method, **options)
        assert r.aov_names() == aovs.aov_names(method), method


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    img = np.ones((4, 4, 3), np.float32)
    target = tmp_path / "a.exr"
    gi.save_image(target, img)
    before = target.read_bytes()

    def fail(self, *a, **k):
        return False

    monkeypatch.setattr(oiio.ImageOutput, "write_image", fail)
    with pytest.raises(OSError, match="cannot write"):
        gi.save_image(target, img * 2)
    # The old file is untouched and no temporary file is left behind.
    assert target.read_bytes() == before and os.listdir(tmp_path) == ["a.exr"]


def test_repr_is_short_and_png_repr_is_the_tone_mapped_beauty(tmp_path, ispm_result):
    r = ispm_result
    text = repr(r)
    # The dataclass repr printed every array (~9.5k characters); now one line.
    assert len(text) < 300 and "ispm" in text and "40x32" in text and "indirect" in text
    png = r._repr_png_()
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
    (tmp_path / "r.png").write_bytes(png)
    back = np.round(gi.read_image(tmp_path / "r.png") * 255).astype(np.uint8)
    assert np.array_equal(back, display.to_srgb8(r.radiance))


def test_tonemaps_differ_as_designed():
    grey = np.full((1, 1, 3), 0.18, np.float32)
    ramp = np.array([[[v, v, v] for v in (0.0, 0.05, 0.18, 1.0, 4.0, 64.0)]], np.float32)
    clip = display.to_display(ramp, "clip")
    filmic = display.to_display(ramp, "filmic")
    aces = display.to_display(ramp, "aces")
    for curve in (clip, filmic, aces):
        assert curve[0, 0].max() < 0.01  # black stays black
        assert (np.diff(curve[0, :, 0]) >= 0).all()  # monotonic
    # clip saturates at 1.0 by 1.0; the filmic curves keep separating 1, 4 and 64.
    assert clip[0, 3, 0] == clip[0, 5, 0] == pytest.approx(1.0, abs=1e-6)
    assert filmic[0, 3, 0] < filmic[0, 4, 0] < filmic[0, 5, 0] <= 1.0
    assert aces[0, 3, 0] < aces[0, 4, 0] < aces[0, 5, 0] <= 1.0
    # Middle grey: sRGB 0.46 clipped, ~0.50 in AgX, ~0.35 in ACES 2.0 SDR (OCIO's value).
    assert display.to_display(grey, "clip")[0, 0, 0] == pytest.approx(0.461, abs=0.002)
    assert display.to_display(grey, "filmic")[0, 0, 0] == pytest.approx(0.50, abs=0.01)
    assert display.to_display(grey, "aces")[0, 0, 0] == pytest.approx(0.349, abs=0.01)
    # Exposure: +1 stop on 0.09 is 0.18.
    assert np.allclose(
        display.to_display(grey / 2, "filmic", 1.0), display.to_display(grey, "filmic")
    )
    # A saturated highlight desaturates towards white in the filmic views but not in clip.
    red = np.array([[[16.0, 0.2, 0.2]]], np.float32)
    assert display.to_display(red, "clip")[0, 0, 1] < 0.5
    assert display.to_display(red, "filmic")[0, 0, 1] > 0.5
    with pytest.raises(ValueError, match="unknown tonemap"):
        display.to_display(grey, "reinhard")
