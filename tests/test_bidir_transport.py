"""Issue 48: `bidir` at its defaults under a sun and a sky, and one frame's steadiness.

- `docs/scenes/sun-sky/sun-sky.xml` (a ground plate and two boxes under a directional sun
  and an image sky), the sun alone and the sky alone: the mean of 4 `bidir` frames (seeds
  1–4) at `max_depth` 7 against `path` at the same depth, within 2% per channel.
- The built-in `cornell` and Mitsuba's Cornell boxes (`tests/scenes/third_party/cbox`,
  `docs/scenes/cornell-box`): the image means of single frames (seeds 1–8) within 3% of
  each other (met on `cbox` alone: strict xfail on the two others), and no pixel of one
  frame's indirect light above a stated multiple of the reference's largest.
- Issue 42's material spheres: the roughness clamp keeps the rough conductors' albedo, and
  a mirror shows the sky and the emitters it reflects (against Mitsuba 3.9.1).

The breakdown by path length behind these numbers: `docs/bench/bidir-depth.md`
(`scripts/bench/bench_bidir_depth.py --terms`).
"""

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import gi

ROOT = Path(__file__).resolve().parent.parent
SUN_SKY = ROOT / "docs" / "scenes" / "sun-sky" / "sun-sky.xml"
CORNELL_BOX = ROOT / "docs" / "scenes" / "cornell-box" / "cornell-box.xml"
CBOX = ROOT / "tests" / "scenes" / "third_party" / "cbox" / "cbox.xml"
SEEDS = range(1, 5)


def sun_sky_variant(keep: str, tmp: Path) -> gi.Scene:
    """sun-sky.xml with both lights (`both`), its sun alone or its sky alone."""
    xml = SUN_SKY.read_text().replace('value="sky.exr"', f'value="{SUN_SKY.parent / "sky.exr"}"')
    drop = {"both": (), "sun": ("envmap",), "sky": ("directional",)}[keep]
    for kind in drop:
        xml, n = re.subn(rf'<emitter type="{kind}".*?</emitter>', "", xml, flags=re.S)
        assert n == 1, kind
    path = tmp / f"sun-sky-{keep}.xml"
    path.write_text(xml)
    return gi.load_scene(path)


@pytest.mark.parametrize("keep", ["both", "sun", "sky"])
def test_sun_and_sky_match_path_at_the_same_depth(keep, tmp_path):
    # 48×36, `bidir` at its defaults (16 bundles, 64 VPLs) but max_depth 7, mean of seeds
    # 1–4; `path` 512 spp at depth 7 (its image mean's noise under 0.2%). Before issue 48
    # the sky's direct light through the bundles' misses made one frame's mean vary by
    # 1.3% (σ), and seeds 1–4 were 2.3–2.7% below `path` under the sky (with or without the
    # sun); its control variate (`bidir.wgsl`) takes that variance away. Measured after:
    # docs/bench/bidir-depth.md. Tolerance 2%, the issue's.
    scene = sun_sky_variant(keep, tmp_path)
    size = (48, 36)
    ref = gi.render(scene, "path", size=size, spp=512, max_depth=7, seed=5).radiance
    frames = [
        gi.render(scene, "bidir", size=size, max_depth=7, seed=s).radiance.mean(axis=(0, 1))
        for s in SEEDS
    ]
    ratio = np.mean(frames, axis=0) / ref.mean(axis=(0, 1))
    assert (np.abs(ratio - 1) < 0.02).all(), ratio


def indirect_max(scene: gi.Scene, method: str, size, **settings) -> float:
    """The largest pixel (mean of RGB) of the light past the direct light: the image at
    `max_depth` 7 less the one at 1 (the same seed)."""
    full = gi.render(scene, method, size=size, max_depth=7, **settings).radiance
    direct = gi.render(scene, method, size=size, max_depth=1, **settings).radiance
    return float((full - direct).mean(axis=2).max())


SPREAD_XFAIL = pytest.mark.xfail(
    strict=True,
    reason="issue 48: one frame's mean varies by σ 1.3–1.5% between seeds (16 seeds)",
)


@pytest.mark.parametrize(
    "name",
    [
        pytest.param("cornell", marks=SPREAD_XFAIL),
        str(CBOX),
        pytest.param(str(CORNELL_BOX), marks=SPREAD_XFAIL),
    ],
)
def test_one_frame_is_steady(name):
    # Issue 48's bound: one frame's image means (48×48, the defaults) within 3% of each
    # other, here over seeds 1–8. Before issue 48 they spread 13–14% (8 seeds, σ 4.0% and
    # 4.4%) on `cornell` and mitsuba.cornell_box() (`docs/scenes/cornell-box`); the light
    # subpaths from every VPL (64 a light instead of one per bundle, 16) and the emitters'
    # photons with stratified directions brought σ down. Measured over 32 seeds
    # (`scripts/probe/bidir_spread.py --seeds 32`, docs/bench/bidir-depth.md): σ 2.0%
    # (`cornell`), 1.2% (Mitsuba 3's `cbox`, `tests/scenes/third_party/cbox`) and 1.7%
    # (mitsuba.cornell_box()); seeds 1–8 spread 4.5%, 2.8% and 4.4%. Seeds 1–4, the bound's
    # seeds before, spread 0.4%, 2.5% and 3.3%: `cornell` passed by luck (its 32 seeds
    # spread 7.8%). Most of σ is the light of two and more bounces (σ at `max_depth` 2:
    # 0.8% and 0.9%). Session 14: each pixel's own bundle-to-VPL pairing offset
    # (`pixel_pair_offset`, `bidir.wgsl`; before, strategy A of every pixel took the same
    # 16 of the 64 subpaths, 0.74% of σ on `cornell` alone): σ over 16 seeds 1.73% →
    # 1.51%, 1.15% → 0.95%, 1.63% → 1.34%; seeds 1–8 spread 4.4%, 2.6%, 3.5%. The issue's
    # 3% over 8 seeds needs σ under about 1% (the range of 8 normal draws is about 2.8σ):
    # not met on `cornell` and mitsuba.cornell_box() (strict xfail: the test fails once
    # it passes).
    scene = gi.load_scene(name)
    means = [
        float(gi.render(scene, "bidir", size=(48, 48), seed=s).radiance.mean()) for s in range(1, 9)
    ]
    spread = (max(means) - min(means)) / np.mean(means)
    assert spread <= 0.03, (means, spread)


@pytest.mark.parametrize("name", ["cornell", str(CBOX), str(CORNELL_BOX)])
def test_one_frame_has_no_hot_spots(name):
    # The largest pixel of one frame's light past the direct light over `path`'s (1024 spp,
    # whose own largest pixel is noise above its smooth image), 48×48, seeds 1–8: with
    # `frame/bidir/spikes.rs` at factor 3 on single pixels 3.8, 2.2 and 3.2 at most (4.3, –
    # and 15 without it); at factor 2, 2×2 blocks first, 2.56, 1.39 and 2.21 (seed by seed in
    # docs/bench/bidir-depth.md, `scripts/probe/bidir_frames.py spread --seeds 8`). Bound:
    # 3 times, over 8 seeds.
    scene = gi.load_scene(name)
    size = (48, 48)
    ref = indirect_max(scene, "path", size, spp=1024, seed=5)
    peaks = [indirect_max(scene, "bidir", size, seed=s) / ref for s in range(1, 9)]
    assert max(peaks) <= 3.0, peaks


def test_spread_spikes_stay_in_radiance_and_indirect_aov_alike():
    # The hot-spot control (`frame/bidir/spikes.rs`, whose unit test checks that it keeps
    # the image's sum) changes the radiance and the `indirect` AOV alike: the radiance is
    # still direct + specular + indirect.
    scene = gi.load_scene(str(CORNELL_BOX))
    r = gi.render(scene, "bidir", size=(32, 32), seed=6)
    np.testing.assert_allclose(
        r.radiance, r.aov("direct") + r.aov("indirect") + r.aov("specular"), rtol=1e-4, atol=1e-5
    )


MATERIALS = ROOT / "tests" / "scenes" / "materials"


@pytest.mark.parametrize("name", ["roughconductor-cu", "roughconductor-al-ggx"])
def test_roughness_clamp_keeps_the_lobes_albedo(name):
    # Issue 42: the rough conductor spheres (GGX α 0.2 under a constant sky and a small area
    # light; Mitsuba 3.9.1 references) were 14–19% dark in `bidir`: the roughness clamp
    # (Tokuyoshi & Ogaki §5) widened the lobe the sky is reflected through (the bundles'
    # density raised α to 1) and GGX at α 1 reflects 31–89% of the light it gets. The clamp
    # now scales the widened lobe by E(α, μ)/E(α', μ) (`raster/shaders/roughness_clamp.wgsl`).
    # Measured at 48×48, seed 3: clamped/unclamped 1.00 (0.83–0.86 before); against Mitsuba
    # Cu 0.97 (the GPU's Schlick stand-in of the conductor's Fresnel, as without the clamp),
    # Al 1.01. Tolerances: 2% between clamped and unclamped (the clamp's Fresnel and table
    # approximations), 5% against Mitsuba (issue 42's bound for `bidir`).
    scene = gi.load_scene(MATERIALS / f"{name}.xml")
    ref = np.array(json.loads((MATERIALS / "references.json").read_text())[name]["mean"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.RenderWarning)
        on = gi.render(scene, "bidir", size=(48, 48), seed=3).radiance.mean(axis=(0, 1))
        off = gi.render(scene, "bidir", size=(48, 48), seed=3, roughness_clamping=False)
    off = off.radiance.mean(axis=(0, 1))
    assert np.all(np.abs(on / off - 1) < 0.02), (on, off)
    assert np.all(np.abs(on / ref - 1) < 0.05), on / ref


def test_a_mirror_shows_the_sky_and_the_emitters_it_reflects():
    # Issue 42's gold sphere (a smooth conductor under a constant sky and a small area
    # light): `bidir` drew neither the sky nor the area light seen in the mirror (no
    # strategy but `frame/bidir/specular_paths.rs`'s delta camera paths reaches them, and
    # they stopped where the mirrored ray left the scene, and counted no emission where it
    # landed): 0.50–0.72 of Mitsuba's image mean per channel. Measured after, 48×48 and
    # 64×64, seeds 1–4: 0.995–1.005. Tolerance 5% (issue 42's bound for `bidir`; one frame's
    # delta camera paths take 4 samples a pixel, and the area light's image in the mirror
    # is a few pixels: its part of the mean varies by ±7% between seeds).
    name = "conductor-au"
    scene = gi.load_scene(MATERIALS / f"{name}.xml")
    ref = np.array(json.loads((MATERIALS / "references.json").read_text())[name]["mean"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.RenderWarning)
        img = gi.render(scene, "bidir", size=(48, 48), seed=3).radiance
    ratio = img.mean(axis=(0, 1)) / ref
    assert np.all(np.abs(ratio - 1) < 0.05), ratio
