"""A Mitsuba `disk` area emitter in the GPU direct light: the importer builds the disk as a
fan of 128 triangles (`gi/mitsuba/shapes.py`), which is more than the closed form's polygon
budget (64 triangles), so its light used to be sampled only (16 points a pixel from the
light tree: a noisy highlight). It is now found round (`scene/emitters/round.rs` `disc`):
one record, its unshadowed light summed per pixel in closed form as the disc's polygon
(`round_lights.wgsl`: Lambert's vector irradiance for the diffuse lobe, linearly
transformed cosines for the glossy one), shadowed by the ratio of its points.

The scene: a one-sided disk light (radius 0.3, radiance 10) facing down over a diffuse
floor, with a GGX rough conductor plate (α 0.1) where the camera sees the disk's
reflection. Against gi's `path` (camera → surface → light, `max_depth` 2, 1024 spp)."""

import numpy as np
import pytest

import gi

SIZE = (64, 48)
SEEDS = (1, 2)

SCENE = """<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world">
      <lookat origin="0, 2, 4.5" target="0, 0, 0.8" up="0, 1, 0"/>
    </transform>
    <film type="hdrfilm">
      <integer name="width" value="64"/><integer name="height" value="48"/>
    </film>
  </sensor>
  <shape type="rectangle">
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    <transform name="to_world">
      <scale value="3"/><rotate x="1" angle="-90"/>
    </transform>
  </shape>
  <shape type="rectangle">
    <bsdf type="roughconductor">
      <string name="distribution" value="ggx"/><float name="alpha" value="0.1"/>
    </bsdf>
    <transform name="to_world">
      <scale value="0.9"/><rotate x="1" angle="-90"/><translate value="0, 0.01, 1.5"/>
    </transform>
  </shape>
  <shape type="disk">
    <emitter type="area"><rgb name="radiance" value="10"/></emitter>
    <transform name="to_world">
      <scale value="0.3"/><rotate x="1" angle="90"/><translate value="0, 1.2, 0"/>
    </transform>
  </shape>
</scene>
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("disk") / "disk.xml"
    path.write_text(SCENE)
    return gi.load_scene(path)


@pytest.fixture(scope="module")
def reference(scene):
    return gi.render(scene, "path", size=SIZE, spp=1024, max_depth=2, seed=7).radiance


@pytest.fixture(scope="module")
def frames(scene):
    return {s: gi.render(scene, "direct", size=SIZE, seed=s).radiance for s in SEEDS}


def highlight(reference: np.ndarray) -> np.ndarray:
    """The plate's highlight: pixels of the reference above a quarter of its brightest
    (the disk's back faces the camera, black: the brightest pixels are the reflection)."""
    lum = reference.mean(axis=2)
    return lum > 0.25 * lum.max()


def test_frame_mean_matches_path(frames, reference):
    """The image mean per channel within 3% of `path`'s (the floor's diffuse light in
    closed form, unshadowed here; the plate by LTC): measured 0.988 (seeds 1-2, lavapipe).
    Before the disk was round (its light sampled from the tree) this passed too."""
    ratios = np.array([frames[s].mean(axis=(0, 1)) / reference.mean(axis=(0, 1)) for s in SEEDS])
    print("disk: image mean / path per seed:", np.round(ratios, 4).tolist())
    assert np.all(np.abs(ratios - 1) <= 0.03), ratios


def test_highlight_matches_path_in_closed_form(frames, reference):
    """The plate's highlight (`highlight`, at least 20 pixels) holds 92-108% of `path`'s
    light in each frame (LTC's GGX fit, ≤ 4.3% in the lobe, plus the reference's noise),
    and is the same light whatever the seed: closed form, not sampled, so two seeds'
    highlights agree pixel by pixel within 2% RMS (a sampled light differs by tens of
    percent). Measured (lavapipe): shares 0.993 in both seeds, RMS 0.0000; before the
    disk was round (main at 63f4290) the RMS was 0.12 and this failed."""
    spot = highlight(reference)
    assert spot.sum() >= 20, spot.sum()
    ref = reference.mean(axis=2)[spot].sum()
    shares = [frames[s].mean(axis=2)[spot].sum() / ref for s in SEEDS]
    a, b = (frames[s].mean(axis=2)[spot] for s in SEEDS)
    rms = float(np.sqrt(np.mean((a - b) ** 2)) / np.mean(a))
    print(f"disk: highlight shares {np.round(shares, 4).tolist()}, seed RMS {rms:.4f}")
    assert all(abs(s - 1) <= 0.08 for s in shares), shares
    assert rms <= 0.02, rms
