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
the wrong handedness moves it by more than 10%.

Khronos' sample models (``khronos_*``: DamagedHelmet, NormalTangentMirrorTest, the
Draco-compressed Box, BoxTextured; tests/scenes/gltf/README.md) under the corpus's horizon
sky (and sun): gi `path` at 64 spp against Cycles with gi's texel lookup and microfacet
model (single-scattering GGX): image means −0.2%, −0.4%, −0.9%, −1.3%, HDR-FLIP 0.019,
0.058, 0.024, 0.025. With Cycles' defaults (Multiscatter GGX, interpolated 8-bit sRGB
texels) the boxes are −2.4% and −3.2% (the light of a rough dielectric that single
scattering loses) and the helmet's emission +12%. The other methods against `path`: see
GLOSSY_GAP (tests/test_glossy_sky.py: the analytic case) and CONVERGED (a method compared
where its smoothing bias has converged, the bias stated)."""

import functools
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from gltf_assets import normal_mapped_quad
from image_metrics import flip

import gi
import gi.gltf

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
    assert len(NAMES) == 12, NAMES
    assert sum(n.startswith("khronos_") for n in NAMES) == 4
    for name in NAMES:
        assert (CORPUS / f"{name}.cycles.exr").is_file(), name


# Khronos' metallic, glossy models lit by the sky: every method but `path` rendered the
# models darker (measured on the model's pixels, 64×64: DamagedHelmet direct −64%, ispm
# −64%, bidir −28%, photon −43%, gather −21%; NormalTangentMirrorTest −28% to −46%), the
# glossy reflection of the sky lost (tests/test_glossy_sky.py; docs/bench/glossy-sky.md).
# Fixed in `gather`, `photon`, `direct` and `ispm` (the mirror test's gold tiles, roughness
# at the glossy clamp 1e-3, were black in `direct` and `ispm`: the G-buffer's 16-bit
# roughness read back as a mirror) and in `bidir` (issue 47: the glossy lobe's sky light by
# env_glossy.wgsl's quadrature in bidir.wgsl; the mirror test's image mean 0.885 → 1.016 of
# `path`, seeds 1–4, scripts/probe/bidir_glossy_sky.py); what is left, measured on the
# image mean against `path` (this test's measure), would be a strict xfail per method: none
# is left.
GLOSSY_GAP: dict[tuple[str, str], str] = {}

# Where a method's estimate at the corpus's settings is biased by its own smoothing and
# converges as the smoothing shrinks, the comparison is made where it has converged.
# (None now. `photon` on NormalTangentMirrorTest was −5.4% at 50k photons, k = 100: the
# k-NN estimate blurred the sun's direct light over the model's 9 cm relief, the bias
# following the radius, not the photon count. Its lights' direct light is now ray traced
# (frame/photon.rs): −0.4% at the corpus's settings.)
CONVERGED: dict[tuple[str, str], dict] = {}


@pytest.mark.parametrize("name", NAMES)
def test_path_matches_cycles(name):
    ref = cycles(name)
    path = render(CORPUS / f"{name}.json")
    assert path.mean() == pytest.approx(ref.mean(), rel=0.03)
    assert flip(ref, path) < 0.08


@functools.cache
def path_mean(name):
    return render(CORPUS / f"{name}.json").mean()


@pytest.mark.parametrize(
    ("name", "method"),
    [
        pytest.param(
            n,
            m,
            marks=pytest.mark.xfail(strict=True, reason=GLOSSY_GAP[(n, m)]),
        )
        if (n, m) in GLOSSY_GAP
        else (n, m)
        for n in NAMES
        for m in OTHERS
    ],
)
def test_every_method_matches_path(name, method):
    img = render(CORPUS / f"{name}.json", method, **CONVERGED.get((name, method), {}))
    assert img.mean() == pytest.approx(path_mean(name), rel=0.05), method


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


def mirror_test_error(img, ref, mask):
    """Mean absolute difference from Cycles over ``mask``, relative to Cycles' mean there."""
    return np.abs(img - ref)[mask].mean() / ref[mask].mean()


def test_khronos_mirror_test_cells_shade_as_in_cycles(monkeypatch):
    """Khronos' NormalTangentMirrorTest (stored tangents, half of its cells with mirrored
    UVs, w = −1) under the horizon sky and the sun. The regions that differ when the
    tangents are wrong are the pixels where gi's image with every stored w negated (a
    reader that ignores handedness) differs from its right image by more than 10% of the
    image mean; there the right image is within 0.3 (relative mean absolute difference) of
    Cycles' and at most half as far as the wrong one's (measured: 8.9% of the pixels,
    0.13 against 0.52)."""
    name = "khronos_normal_tangent_mirror"
    ref = cycles(name)
    right = render(CORPUS / f"{name}.json")

    def negated_w(arrays, n, where):
        t = real_tangents(arrays, n, where)
        t[:, 3] = -t[:, 3]
        return t

    real_tangents = gi.gltf._tangents
    monkeypatch.setattr(gi.gltf, "_tangents", negated_w)
    wrong = render(CORPUS / f"{name}.json")
    mask = (np.abs(wrong - right).mean(axis=2) > 0.1 * right.mean())[..., None].repeat(3, 2)
    assert mask.mean() > 0.05  # the test reads a good part of the image
    got, bad = mirror_test_error(right, ref, mask), mirror_test_error(wrong, ref, mask)
    assert got < 0.3 and got < 0.5 * bad, (got, bad)


HELMET = CORPUS / "khronos" / "DamagedHelmet" / "DamagedHelmet.glb"
HORIZON = CORPUS / "khronos" / "horizon.exr"


def load_helmet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gi.load_scene(HELMET)


def helmet_pixels():
    """The pixels wholly on the helmet at 64×64 in the file's own framing (its edge pixels
    and their neighbours left out)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the file alone is "nearly black": said, known
        r = gi.Renderer(load_helmet(), "path", spp=1, size=(64, 64)).render(aovs=True)
    hit = (r.depth if r.depth.ndim == 2 else r.depth[..., 0]) > 0
    pad = np.pad(hit, 1)
    return np.logical_and.reduce(
        [pad[1 + dy : 65 + dy, 1 + dx : 65 + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    )


def test_damaged_helmet_is_lit_by_env_on_the_command_line(tmp_path):
    """The issue's must-show: ``gi render DamagedHelmet.glb --env HDR -o out`` (the default
    method, 64×64) lights the asset: its pixels are more than 10× those of the file alone
    (emission only, with the "nearly black" message; measured 26×)."""
    import subprocess
    import sys

    helmet = helmet_pixels()
    assert helmet.mean() > 0.1

    def run(*extra):
        out = tmp_path / "out.exr"
        cmd = [sys.executable, "-m", "gi.cli", "render", str(HELMET), "--size", "64x64"]
        done = subprocess.run([*cmd, "-q", "-o", str(out), *extra], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return gi.read_image(out)[..., :3][helmet].mean(), done.stderr

    bare, said = run()
    assert "nearly black" in said and "--env" in said
    lit, said = run("--env", str(HORIZON))
    assert "nearly black" not in said
    assert lit > 10 * bare and lit > 0.05, (bare, lit)


def test_damaged_helmet_is_lit_by_the_viewer_panels_file():
    """The same in the viewer (its default method): the Environment panel's file (the
    folder of the horizon sky) lights the helmet, more than 3× the file alone (the frames'
    sRGB decoded; measured 4.9× with the interactive preset, the emissive parts being much
    of the file alone's light); "scene" gives the emission-only image back (within 10%)."""
    from gi.viewer import messages as m
    from gi.viewer.engine import Engine

    helmet = helmet_pixels()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "nearly black" until the panel lights it
        engine = Engine(
            load_helmet(),
            gi.DEFAULT_METHOD,
            {"size": (64, 64)},
            on_frame=lambda frame: None,
            on_event=lambda client, event: None,
            env_dir=HORIZON.parent,
        )
    engine.start()
    try:

        def helmet_mean():
            frame = engine.wait_frame(timeout=120)
            assert frame is not None
            srgb = frame.pixels.astype(np.float64)[helmet][..., :3] / 255
            linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
            return float(linear.mean())

        dark = helmet_mean()
        assert "file: horizon.exr" in engine.state()["environment"]["choices"]
        engine.submit(m.Environment("file: horizon.exr"), 1, wait=True).result(timeout=120)
        lit = helmet_mean()
        assert lit > 3 * dark, (dark, lit)
        engine.submit(m.Environment("scene"), 1, wait=True).result(timeout=120)
        assert helmet_mean() == pytest.approx(dark, rel=0.1)
    finally:
        engine.stop()
