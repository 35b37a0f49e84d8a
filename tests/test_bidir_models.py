"""Issue 42: `bidir`'s VPLs and ray-bundle hits shade Mitsuba's exact models
(raster/shaders/bidir_models.wgsl), not only its pixels.

The scene: a spot light aimed at a wall of one of Mitsuba's models (a rough Cu conductor,
a nonlinear rough plastic under a Beckmann coating), a diffuse floor in front of it that
the spot does not reach, and a camera that sees only the floor: all of the image is light
that came off the model wall (the interreflection's middle vertex is a VPL on the wall, or
a bundle's hit there). `path` (the CPU's exact models, matched to Mitsuba in
`crates/core/src/bsdf/tests_models.rs`) is the reference.
"""

import warnings

import numpy as np
import pytest

import gi

SCENE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="1.5, 2.2, 3.2" target="1.2, -1, -0.3"/>
        </transform><film type="hdrfilm"><integer name="width" value="48"/>
        <integer name="height" value="48"/></film></sensor>
    <emitter type="spot">
        <transform name="to_world"><lookat origin="1.5, 0.5, 0" target="-1, 0.5, 0"/></transform>
        <float name="cutoff_angle" value="25"/><float name="beam_width" value="20"/>
        <rgb name="intensity" value="30"/>
    </emitter>
    <shape type="rectangle"><transform name="to_world">
        <scale value="2"/><rotate y="1" angle="90"/><translate x="-1" y="1"/></transform>
        WALL</shape>
    <shape type="rectangle"><transform name="to_world">
        <scale value="3"/><rotate x="1" angle="-90"/><translate y="-1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf></shape>
</scene>
"""

WALLS = {
    "roughconductor-cu": '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
    '<float name="alpha" value="0.3"/></bsdf>',
    "roughplastic-beckmann": '<bsdf type="roughplastic"><boolean name="nonlinear" value="true"/>'
    '<string name="distribution" value="beckmann"/><float name="alpha" value="0.2"/>'
    '<rgb name="diffuse_reflectance" value="0.8, 0.7, 0.2"/></bsdf>',
}
SIZE = (48, 48)


def wall_scene(tmp_path, wall: str) -> gi.Scene:
    path = tmp_path / f"{wall}.xml"
    path.write_text(SCENE.replace("WALL", WALLS[wall]))
    with warnings.catch_warnings():  # Mitsuba's spot falls off linearly in angle, gi's not
        warnings.filterwarnings("ignore", ".*spot falls off", gi.AssetWarning)
        return gi.load_scene(path)


def bidir_mean(scene: gi.Scene, seeds, **settings) -> np.ndarray:
    """The mean over `seeds` of `bidir`'s image means per channel; no warning allowed (the
    models are shaded exactly everywhere)."""
    means = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for s in seeds:
            img = gi.render(scene, "bidir", size=SIZE, max_depth=3, seed=s, **settings)
            means.append(img.radiance.mean(axis=(0, 1)))
    return np.mean(means, axis=0)


@pytest.mark.parametrize("wall", sorted(WALLS))
def test_interreflection_through_a_model_matches_path(tmp_path, wall):
    # `bidir` (mean of seeds 1-8, max_depth 3) against `path` (256 spp, max_depth 3: its
    # mean's noise under 0.3%). Measured: Cu 1.016-1.017, plastic 1.008 per channel (one
    # seed's frame: 0.957-1.057 and 0.982-1.029, the spot's 64 VPLs on the wall). With the
    # VPLs and bundle hits on the uber stand-ins (main before bidir_models.wgsl named their
    # models; seeds 1-4) Cu was 0.886-0.888 (Schlick's Fresnel and GGX for the conductor's
    # complex index and Beckmann lobe), the plastic 1.001-1.012. Tolerance 4%: issue 42's 5%
    # for `bidir`, less the 8 seeds' averaging (σ of their mean about 1.4% for Cu).
    scene = wall_scene(tmp_path, wall)
    ref = gi.render(scene, "path", size=SIZE, spp=256, max_depth=3, seed=5).radiance
    ratio = bidir_mean(scene, range(1, 9)) / ref.mean(axis=(0, 1))
    assert np.all(np.abs(ratio - 1) < 0.04), f"{wall}: {ratio}"


@pytest.mark.parametrize("wall", sorted(WALLS))
def test_model_clamp_keeps_the_interreflections_energy(tmp_path, wall):
    # The roughness clamp (Tokuyoshi & Ogaki §5) widens the model's lobe at the VPLs and
    # bundle hits on the wall and scales it by the model's own E(α, μ)/E(α', μ)
    # (bidir_models.wgsl `eval_clamped_model`): the image mean with the clamp equals the
    # one without it (the same seeds) within 2%, the clamp's stated bias (split-sum Fresnel,
    # table interpolation). Measured (seeds 1-2): Cu 1.004, plastic 1.0004.
    scene = wall_scene(tmp_path, wall)
    on = bidir_mean(scene, range(1, 3))
    off = bidir_mean(scene, range(1, 3), roughness_clamping=False)
    assert np.all(np.abs(on / off - 1) < 0.02), f"{wall}: {on / off}"
