"""Published Mitsuba scenes, committed untouched with their licences
(`tests/scenes/third_party/*/README.md`), load with no warning and render like Mitsuba 3.9.1
(`reference.exr`, `scripts/data/mitsuba_third_party.py`: 4096 spp, path tracer, max_depth
65 = gi's 64 scattering events, box filter).

- cornell-box: Bitterli's Cornell box (Mitsuba 0.5 format: camelCase, `toWorld`, ldrfilm);
- cbox: Mitsuba 3's own Cornell box (reflectances and emission as sampled spectra);
- veach-mis: Bitterli's Veach MIS scene (0.5 format; Beckmann rough conductors with complex
  IOR, Mitsuba's models since branch `materials`).

Tolerance: `path`'s image mean within 2% per channel. Noise: over 4 seeds the per-channel
means at these sizes and spp spread by 0.08-0.18% (cbox, cornell-box, 64×64 at 64 spp; 2-3 s
each here); veach-mis's tiny bright sphere (radius 0.05, radiance 3039) seen in its glossy
plates spreads its mean by ≈1.5% at 128 spp, so it renders 1024 spp at 80×45 (σ ≈ 0.5%,
35 s on 2 shared cores); the references' standard errors are below 0.3%. 2% is over 10σ for
the Cornell boxes and 4σ for veach-mis: a failure is a bias, not noise. veach-mis measures
1.018, 1.027, 1.026 today (seed 7; 1.016-1.027 over seeds 5-8 at 128 spp with the
directly seen light masked out) with the uber BSDF's GGX and Schlick F0 in place of its
Beckmann complex-IOR conductors; with branch `materials`' models it loads without a warning
and its checks pass.

`mitsuba-layers` (gi's own scene, `scripts/data/mitsuba_layers.py`, Mitsuba `volpath`
reference: its `path` integrator treats a mask as opaque for shadow rays) checks `mask`,
`normalmap` and `bumpmap`: each rectangle's mean within 3% of Mitsuba's.
"""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import gi

THIRD_PARTY = Path(__file__).parent / "scenes" / "third_party"
# scene -> (file, render size, spp)
SCENES = {
    "cornell-box": ("scene.xml", (64, 64), 64),
    "cbox": ("cbox.xml", (64, 64), 64),
    "veach-mis": ("scene.xml", (80, 45), 1024),
}
# Scenes whose materials gi approximates (none since branch `materials`: Beckmann rough
# conductors with complex IOR are Mitsuba's models).
NEEDS_MATERIALS: set[str] = set()


def load(name):
    file = SCENES[name][0]
    return gi.load_scene(THIRD_PARTY / name / file)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_scene_is_committed_with_its_licence_and_reference(name):
    d = THIRD_PARTY / name
    assert (d / "LICENSE.txt").stat().st_size > 0 and (d / "README.md").stat().st_size > 0
    meta = json.loads((d / "reference.json").read_text())
    ref = gi.read_image(d / "reference.exr")[..., :3]
    assert list(ref.shape[1::-1]) == meta["size"] and meta["spp"] >= 4096
    assert meta["max_depth"] == 65 and meta["rfilter"] == "box"
    # The reference's own noise is far below the 2% checked against it.
    assert max(np.array(meta["stderr"]) / np.array(meta["mean"])) < 0.003
    assert ref.mean(axis=(0, 1)) == pytest.approx(meta["mean"], rel=2e-3)  # half floats


WAIT_FOR_MATERIALS = [
    pytest.param(n, marks=pytest.mark.xfail(strict=True, reason="needs branch materials"))
    if n in NEEDS_MATERIALS
    else n
    for n in sorted(SCENES)
]


@pytest.mark.parametrize("name", WAIT_FOR_MATERIALS)
def test_scene_loads_untouched_without_a_warning(name):
    text = (THIRD_PARTY / name / SCENES[name][0]).read_text()
    assert "<scene version=" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load(name)


@pytest.mark.parametrize("name", WAIT_FOR_MATERIALS)
def test_path_matches_mitsuba_within_2_percent(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.AssetWarning)  # veach-mis until `materials`
        scene = load(name)
    _file, size, spp = SCENES[name]
    img = gi.render(scene, "path", spp=spp, seed=7, size=size).radiance
    ref = gi.read_image(THIRD_PARTY / name / "reference.exr")[..., :3]
    ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
    assert np.all(np.abs(ratio - 1) <= 0.02), (name, ratio)


def test_includes_build_the_same_scene():
    """Mitsuba's `cbox-spectral.xml` (`<include>`s of fragments, its area emitter declared
    at the top level and referenced by id) is `cbox.xml`: same camera, materials (the
    emitting one named by its line), placements; loaded without a warning."""
    from gi.mitsuba.elements import parse_xml
    from gi.mitsuba.translator import Translator

    def translate(path):
        t = Translator(path)
        t.run(parse_xml(path.read_bytes(), str(path)))
        return t

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = translate(THIRD_PARTY / "cbox" / "cbox-spectral.xml")
        gi.load_scene(THIRD_PARTY / "cbox" / "cbox-spectral.xml")
    b = translate(THIRD_PARTY / "cbox" / "cbox.xml")
    assert a.camera == b.camera
    assert sorted(a.materials.values(), key=str) == sorted(b.materials.values(), key=str)
    assert [o["transform"] for o in a.objects] == [o["transform"] for o in b.objects]


def test_old_format_scene_places_camera_and_shapes():
    """Bitterli's Cornell box: the camera at (0, 1, 6.8) looking down -z (its `toWorld`
    matrix), every wall placed (none left at the origin)."""
    scene = load("cornell-box")
    r = gi.render(scene, "path", spp=1, seed=1, size=(32, 32))
    assert (r.depth > 0).all()  # a closed box seen from its open side: every pixel hits
    assert 5.5 < r.depth[16, 16] < 8.0  # the back wall, about 7.8 away along the axis


LAYERS = Path(__file__).parent / "scenes" / "mitsuba-layers"


def rect_region(img, centre, half_extent=0.45):
    """Pixels of the rectangle centred at x = `centre` (camera at z = 5, fov 40° along x)."""
    h, w = img.shape[:2]
    half_x = 5 * np.tan(np.radians(20))
    half_y = half_x * h / w
    x0, x1 = (
        int((c + half_x) / (2 * half_x) * w) for c in (centre - half_extent, centre + half_extent)
    )
    y0, y1 = (int((half_y - c) / (2 * half_y) * h) for c in (half_extent, -half_extent))
    return img[y0:y1, x0:x1]


def test_mask_normalmap_bumpmap_match_mitsuba():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = gi.load_scene(LAYERS / "scene.xml")
    # The normal and bump maps' approximations are named (the mask's 0/1 opacity is exact):
    # Mitsuba's shadowing term (its normal map is 1.3% darker here), the bump map's baking.
    reasons = sorted(w.message.reason for w in caught)
    assert len(reasons) == 2 and reasons[0].startswith("Mitsuba's shadowing"), reasons
    assert reasons[1].startswith("bump map baked") and "Estevez" in reasons[1], reasons
    img = gi.render(scene, "path", spp=64, seed=3).radiance
    ref = gi.read_image(LAYERS / "reference.exr")[..., :3]
    for name, centre in (("mask", -1.2), ("normalmap", 0.0), ("bumpmap", 1.2)):
        ratio = rect_region(img, centre).mean() / rect_region(ref, centre).mean()
        # Measured at 256 spp: mask 1.006, normalmap 1.013 (gi's 0.696 is the analytic
        # 0.8/π · 3 · cos 24.4°; Mitsuba's is 1.27% lower by its shadowing term
        # 2/(1 + √(1 + α² tan² θ)), α² = tan² 30°/8, tan² θ = 1.25), bumpmap 1.002.
        assert abs(ratio - 1) < 0.03, (name, ratio)
    # The bump map's slope, not only its mean: the profile across the rectangle (brightest
    # where the sine's slope turns the normal towards the light) column by column. A flipped
    # sign would mirror it (0.34 ... 0.64 ... 0.36 left to right in Mitsuba's).
    gi_cols = rect_region(img, 1.2).mean(axis=(0, 2))
    mi_cols = rect_region(ref, 1.2).mean(axis=(0, 2))
    assert np.abs(gi_cols - mi_cols).max() < 0.05 * mi_cols.max(), (gi_cols, mi_cols)
    # The cut-out is seen: about half of the masked rectangle is its lit white (0.8/π · 3 ·
    # cos 48° ≈ 0.51), the rest the grey wall behind it (at most 0.3/π · 3 · 0.67 ≈ 0.19).
    bright = rect_region(img, -1.2).mean(axis=-1) > 0.4
    assert 0.35 < bright.mean() < 0.65, bright.mean()
    # ... in Mitsuba's checker pattern, not its mirror (the rectangle's v runs up +y): the
    # cells agree pixel by pixel but for the cells' edges.
    same = bright == (rect_region(ref, -1.2).mean(axis=-1) > 0.4)
    assert same.mean() > 0.9, same.mean()


# The other methods on the scenes whose materials gi renders as Mitsuba does (64×64, seed
# 7, max_depth 64): `photon`/`gather` within 3%, `ispm`/`bidir` within 5% of Mitsuba's
# image mean per channel (issue 42). Measured here: cornell-box photon 0.996-1.000, gather
# 1.008-1.010, ispm 1.007-1.008, bidir 0.961-0.977 (8 passes); cbox photon 0.989-0.990,
# gather 1.000, ispm 1.011-1.013, bidir 0.989-0.994 (16 passes; 0.991-0.995 at 128×128).
# `bidir` was 0.839-0.872 on cbox before the eye views' near plane moved to the scene's
# bounding box (`raster::camera_view`): at far · 1e-5 the luminaire, 0.5 units under the
# ceiling 1100 units away, z-fought with it and vanished from whole passes of some
# sub-pixel offsets (the test failed then).
OTHER = {
    "photon": ({"photons": 200_000, "spp": 16}, 0.03),
    "gather": ({"photons": 200_000, "spp": 16}, 0.03),
    "ispm": ({"photons": 200_000, "spp": 16}, 0.05),
    "bidir": ({"spp": 16, "progressive": True, "passes": 16}, 0.05),
}


@pytest.mark.parametrize(
    "name, method",
    [(n, m) for n in ("cbox", "cornell-box") for m in OTHER],
)
def test_other_methods_match_mitsuba(name, method):
    settings, tolerance = OTHER[method]
    settings = dict(settings)
    passes = settings.pop("passes", None)
    r = gi.Renderer(load(name), method, size=(64, 64), seed=7, max_depth=64, **settings)
    img = (r.render_progressive(passes=passes) if passes else r.render()).radiance
    ref = gi.read_image(THIRD_PARTY / name / "reference.exr")[..., :3]
    ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
    assert np.all(np.abs(ratio - 1) <= tolerance), (name, method, ratio)


@pytest.mark.parametrize("light, expected", [("0, -1, -1", 0.1537), ("0, 1, -1", 0.0412)])
def test_normal_map_y_and_rectangle_uv_as_mitsuba(tmp_path, light, expected):
    """A normal map tilting every normal 30° towards the map's +y, on Mitsuba's rectangle
    (whose v runs up +y), lit from the upper or the lower front: Mitsuba's map frame is
    (∂p/∂u, n × ∂p/∂u, n), so +y tilts towards world +y. Mitsuba 3.9.1 renders 0.1537 and
    0.0412 at the centre (with `use_shadowing_function` false), the analytic
    0.5/π · (±sin 30° + cos 30°)/√2."""
    tilt = np.radians(30)
    n = np.array([0.0, np.sin(tilt), np.cos(tilt)]) * 0.5 + 0.5
    gi.save_image(tmp_path / "ny.exr", np.broadcast_to(n, (4, 4, 3)).astype(np.float32))
    (tmp_path / "s.xml").write_text(
        f"""<scene version="3.0.0"><sensor type="perspective"><float name="fov" value="40"/>
<transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
</film></sensor><shape type="rectangle"><bsdf type="normalmap">
<boolean name="use_shadowing_function" value="false"/>
<texture type="bitmap" name="normalmap"><string name="filename" value="ny.exr"/>
<boolean name="raw" value="true"/></texture><bsdf type="diffuse"/></bsdf></shape>
<emitter type="directional"><vector name="direction" value="{light}"/></emitter></scene>"""
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no shadowing term asked for: nothing approximated
        scene = gi.load_scene(tmp_path / "s.xml")
    r = gi.render(scene, "path", spp=4, seed=1)
    assert r.radiance[6:10, 6:10].mean() == pytest.approx(expected, rel=0.01)


# The material spheres (one per BSDF of issue 42, roughdielectric included) are
# tests/scenes/materials/, checked by tests/test_materials_mitsuba.py.
