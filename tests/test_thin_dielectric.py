"""Mitsuba's `thindielectric` (issue 44 item 4, issue 42): a thin slab of glass, reflecting
R' = R + T²R/(1 − R²) = 2R/(1 + R) times `specular_reflectance` and passing the rest, times
`specular_transmittance`, straight through (gi's `thin_glass`, `Material::thin`; before, the
importer refused it). tests/scenes/thin-pane/ (scripts/data/thin_pane_scene.py): a coloured
pane tilted between an area light and a floor, with Mitsuba 3.9.1's `path` image (4096
spp, its mean's standard error 0.3%).

Every method traces thin glass on the CPU as it traces glass (its sampled lobes: `path`,
`photon`, `gather`; `ispm`'s and `bidir`'s caustic light paths and specular images); the
GPU passes keep it opaque in their shadow maps, as glass, and `direct` (direct light only)
leaves the light through it out, as `path` at `max_depth` 1 does.
"""

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import gi
from gi.mitsuba.elements import parse_xml
from gi.mitsuba.translator import Translator

DIR = Path(__file__).parent / "scenes" / "thin-pane"
XML = DIR / "thin-pane.xml"


def reference() -> tuple[np.ndarray, np.ndarray]:
    meta = json.loads((DIR / "reference.json").read_text())
    return np.array(meta["mean"]), np.array(meta["standard_error"])


@pytest.fixture(scope="module")
def scene():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return gi.load_scene(XML)


def translate(path: Path) -> Translator:
    t = Translator(path)
    t.run(parse_xml(path.read_bytes(), str(path)))
    return t


def test_the_pane_is_read_as_mitsuba_defines_it():
    (pane,) = [m for m in translate(XML).materials.values() if "thin_glass" in m]
    assert pane["thin_glass"] == pytest.approx([1.0, 0.8, 0.6])
    assert pane["transmission"] == pytest.approx([0.9, 0.9, 0.7])
    assert pane["ior"] == pytest.approx(1.5 / 1.000277)  # ext_ior: air by default


def test_old_camel_case_names_are_read(tmp_path):
    old = XML.read_text().replace('version="3.0.0"', 'version="0.6.0"')
    for new, camel in [
        ("int_ior", "intIOR"),
        ("specular_reflectance", "specularReflectance"),
        ("specular_transmittance", "specularTransmittance"),
        ("to_world", "toWorld"),
        ("max_depth", "maxDepth"),
        ("sample_count", "sampleCount"),
    ]:
        old = old.replace(f'name="{new}"', f'name="{camel}"')
    path = tmp_path / "old.xml"
    path.write_text(old.replace("<lookat", "<lookAt"))
    assert translate(path).materials == translate(XML).materials


@pytest.mark.parametrize(
    "bsdf, words",
    [
        ('<rgb name="specular_transmittance" value="0"/>', "specular_transmittance 0"),
        ('<float name="int_ior" value="9"/>', "not in [1, 4]"),
        ('<float name="alpha" value="0.1"/>', "alpha"),
    ],
)
def test_what_gi_cannot_render_is_refused(tmp_path, bsdf, words):
    path = tmp_path / "s.xml"
    xml = XML.read_text()
    start = xml.index('<bsdf type="thindielectric">')
    end = xml.index("</bsdf>", start)
    path.write_text(xml[:start] + f'<bsdf type="thindielectric">{bsdf}' + xml[end:])
    with pytest.raises(gi.SceneError, match=re.escape(words)):
        gi.load_scene(path)


def test_path_matches_mitsuba(scene):
    # 256 spp (mean's noise ~0.3%) against Mitsuba's 4096 (0.3%): 2% per channel, the issue's.
    mean, se = reference()
    assert (se / mean).max() < 0.005
    ours = gi.render(scene, "path", spp=256, seed=3).radiance[..., :3].reshape(-1, 3).mean(0)
    ratio = ours / mean
    print(ratio)
    assert np.all(np.abs(ratio - 1) < 0.02), ratio


# The tolerances: `photon`/`gather` 3%, `ispm`/`bidir` 5% of the reference mean
# (one frame, seeds 1-2, at the methods' defaults).
TOLERANCE = {"photon": 0.03, "gather": 0.03, "ispm": 0.05, "bidir": 0.05}


@pytest.mark.parametrize("method", sorted(TOLERANCE))
def test_other_methods_match_mitsuba(scene, method):
    mean, _ = reference()
    for seed in (1, 2):
        r = gi.render(scene, method, seed=seed)
        ratio = r.radiance[..., :3].reshape(-1, 3).mean(0) / mean
        print(method, seed, ratio)
        assert np.all(np.abs(ratio - 1) < TOLERANCE[method]), (seed, ratio)


def off_the_pane(result) -> np.ndarray:
    """Pixels whose first surface is not the pane (the plane through (0, 1, 0) of normal
    (0, sin 60°, cos 60°))."""
    n = np.array([0.0, np.sin(np.pi / 3), 0.5])
    return np.abs((result.position - [0.0, 1.0, 0.0]) @ n) > 1e-3


def test_direct_matches_the_direct_light(scene):
    # `direct` is the direct light alone: `path` at max_depth 1 (256 spp), 5%, off the pane.
    # On the pane `path` at depth 1 shows the light reflected there (one delta bounce, as
    # Mitsuba's `direct` counts it), which gi's `direct` leaves out for all glass (issue 42,
    # `directspec`): 44% of this image's depth-1 light.
    p = gi.render(scene, "path", spp=256, seed=3, max_depth=1)
    mask = off_the_pane(p)
    assert mask.mean() > 0.8
    ref = p.radiance[..., :3][mask].mean()
    for seed in (1, 2):
        ratio = gi.render(scene, "direct", seed=seed).radiance[..., :3][mask].mean() / ref
        print(seed, ratio)
        assert abs(ratio - 1) < 0.05, ratio


def test_ispm_names_its_bounce_map_approximation_under_a_point_light(tmp_path):
    # `ispm`'s GPU bounce maps take a point or spot light's photons' first scatter on the
    # stand-in (straight through, no reflection): a RenderWarning naming the material.
    xml = XML.read_text().replace(
        "</scene>",
        '<emitter type="point"><point name="position" x="0" y="1.8" z="0.5"/>'
        '<rgb name="intensity" value="2"/></emitter>\n</scene>',
    )
    path = tmp_path / "point.xml"
    path.write_text(xml)
    scene = gi.load_scene(path)
    with pytest.warns(gi.RenderWarning, match="thin glass"):
        gi.Renderer(scene, "ispm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gi.Renderer(scene, "path")
