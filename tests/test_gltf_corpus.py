"""The glTF corpus (``tests/scenes/gltf/``, written by ``scripts/data/gltf_corpus.py``)
against Blender Cycles' images of the same scenes (committed; CI does not run Blender).

Each scene is a glTF asset under a sun and a constant sky, or (``lit_room``) lit by its own
``KHR_lights_punctual`` point and spot lights. Measured (gi `path` at 256 spp against
Cycles at 1024, 64×64): image means within +1.8% (normal-mapped bumps: stored, MikkTSpace,
mirrored, quantized; the texture-transform checker), −1.3% (the sphere, plain and Draco)
and −0.9% (lit_room); HDR-FLIP 0.018 (bumps), 0.024 (sphere), 0.046 (lit_room), 0.053
(checker). The material models
differ there: gi's glTF material is its uber BSDF (Lambert diffuse times (1 − metallic)
plus a GGX layer of F0 = 0.04 with Schlick's Fresnel), Cycles' is the Principled BSDF (an
energy-conserving dielectric layer over its diffuse, multiple scattering GGX), about 2% of
the light of a rough dielectric; the checker's edges are filtered differently (Cycles
interpolates 8-bit textures before decoding sRGB). Tolerances: 3% on the mean (the issue's
bound; 1.2–1.7× the measured gap), FLIP below 0.08, and every other method within 5% of
`path`.

The bumps' shading: the ratio of the bumps' upper-right to lower-right quadrants (lit and
unlit sides for the sun from the upper right) matches Cycles' within 2%; a tangent frame of
the wrong handedness moves it by more than 10%."""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from gltf_assets import normal_mapped_quad
from image_metrics import flip

import gi

CORPUS = Path(__file__).parent / "scenes" / "gltf"
NAMES = sorted(p.stem for p in CORPUS.glob("*.json"))
OTHERS = {
    "direct": {"spp": 4},
    "ispm": {"spp": 4, "photons": 50_000},
    "bidir": {"spp": 4},
    "photon": {"spp": 16, "photons": 50_000},
    "gather": {"spp": 16, "photons": 50_000},
}


def cycles(name):
    return gi.read_image(CORPUS / f"{name}.cycles.exr")[..., :3]


def render(scene_path, method="path", **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.AssetWarning)
        scene = gi.load_scene(scene_path)
    settings = {"spp": 64, "seed": 1} if method == "path" else OTHERS[method]
    return gi.render(scene, method, **{**settings, **kw}).radiance


def quadrant_ratio(img):
    """Upper-right over lower-right quadrants of the 4×4 bumps (16×16 pixels each)."""
    lum = img.mean(axis=2)
    yy, xx = np.mgrid[0 : lum.shape[0], 0 : lum.shape[1]]
    fx, fy = xx % 16 - 7.5, -(yy % 16 - 7.5)
    return lum[(fx > 2) & (fy > 2)].mean() / lum[(fx > 2) & (fy < -2)].mean()


def test_corpus_is_complete():
    assert len(NAMES) == 8, NAMES
    for name in NAMES:
        assert (CORPUS / f"{name}.cycles.exr").is_file(), name


@pytest.mark.parametrize("name", NAMES)
def test_path_matches_cycles_and_every_method_matches_path(name):
    ref = cycles(name)
    path = render(CORPUS / f"{name}.json")
    assert path.mean() == pytest.approx(ref.mean(), rel=0.03)
    assert flip(ref, path) < 0.08
    for method in OTHERS:
        img = render(CORPUS / f"{name}.json", method)
        assert img.mean() == pytest.approx(path.mean(), rel=0.05), method


@pytest.mark.parametrize("name", [n for n in NAMES if n.startswith("bumps")])
def test_bumps_shade_as_in_cycles(name):
    expected = quadrant_ratio(cycles(name))
    assert expected > 1.05  # the sun lights the bumps' upper-right sides
    for method in ("path", "direct"):
        got = quadrant_ratio(render(CORPUS / f"{name}.json", method))
        assert got == pytest.approx(expected, rel=0.02), method


def test_wrong_handedness_is_seen_by_the_bump_test(tmp_path):
    normal_mapped_quad(tmp_path / "bumps.glb", tangents="wrong-w")
    scene = json.loads((CORPUS / "bumps.json").read_text())
    (tmp_path / "bumps.json").write_text(json.dumps(scene))
    got = quadrant_ratio(render(tmp_path / "bumps.json"))
    assert abs(got / quadrant_ratio(cycles("bumps")) - 1) > 0.1
