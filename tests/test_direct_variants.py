"""The direct light's pipelines are compiled for the kinds of light and material a scene
has (`raster/direct_variant.rs`): a scene without specular or emitting materials compiles
neither. A material update that brings one in must switch the pipelines: the frame after
it is the frame of a renderer that had the material from the start, bit for bit, and it
shows the change."""

import numpy as np
import pytest

import gi

SIZE = (48, 36)
CHANGES = {
    # Lambert's lobe alone before (cornell's materials): a glossy lobe appears.
    "specular": {"white": {"specular": [0.5, 0.5, 0.5], "roughness": 0.2}},
    # A Fresnel-weighted diffuse lobe (no specular colour).
    "fresnel": {"white": {"fresnel": True}},
    # An emitting surface (its emission is read from the G-buffer).
    "emission": {"red": {"emission": [3.0, 0.5, 0.5]}},
}


def frame(r: gi.Renderer) -> np.ndarray:
    return np.asarray(r.render(seed=3).radiance)


@pytest.mark.parametrize("name", sorted(CHANGES))
def test_a_material_update_switches_the_direct_pipelines(name):
    change = CHANGES[name]
    r = gi.Renderer(gi.load_scene("cornell"), "direct", size=SIZE, seed=3)
    before = frame(r)
    r.update(materials=change)
    after = frame(r)
    fresh = gi.Renderer(gi.load_scene("cornell"), "direct", size=SIZE, seed=3)
    fresh.update(materials=change)
    want = frame(fresh)
    assert np.array_equal(after, want)
    assert np.abs(after - before).max() > 1e-3
