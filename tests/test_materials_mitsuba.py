"""Mitsuba 3's material models in gi (issue 42, item 3): single-material spheres
(tests/scenes/materials/, written with their references by
scripts/data/materials_spheres.py; CI never runs Mitsuba) load without a warning and `path`
renders each within 2% of Mitsuba's image mean per channel and FLIP ≤ 0.05, each 8×8 block
within 7%.

The references are Mitsuba 3.9.1 `path` (scalar_rgb), 64×64, 4096 samples per pixel in 8
batches: their means are known to better than 0.05% (references.json). Both renderers use
a box pixel filter; Mitsuba's sphere is exact, gi's the importer's tessellated one with
smooth normals (its silhouette differs by a fraction of a pixel). gi's `path` at 256 spp.
The GPU methods' direct light, `ispm`'s photon estimates and first bounce and `bidir`'s
pixels, VPLs and ray bundle hits shade the exact models (raster/exact_models.rs,
raster/shaders/bidir_models.wgsl; tests/test_bidir_models.py for the interreflections
through them). `ispm` and `bidir` are held to 5% of Mitsuba's mean; `direct`, `ispm` and
`bidir` on the rough spheres (the GPU direct light and, in `bidir`, the sky through its
bundles are the whole image there) to 1%, and `direct` on every sphere to 2% of Mitsuba's
`direct` integrator (the light met one delta scattering from the camera included)."""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from image_metrics import flip

import gi

SCENES = Path(__file__).resolve().parent / "scenes" / "materials"
META = json.loads((SCENES / "references.json").read_text()) if SCENES.exists() else {}
NAMES = sorted(META)


def test_every_sphere_has_a_reference():
    assert set(NAMES) >= {
        "plastic",
        "roughplastic-ggx",
        "roughplastic-beckmann",
        "conductor-au",
        "roughconductor-cu",
        "roughconductor-al-ggx",
        "roughdielectric",
    }
    for name in NAMES:
        assert (SCENES / f"{name}-reference.exr").stat().st_size < 80_000
        assert len(META[name]["direct"]["mean"]) == 3  # Mitsuba's `direct`


@pytest.mark.parametrize("name", NAMES)
def test_path_matches_mitsuba(name):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing approximated, nothing ignored
        scene = gi.load_scene(SCENES / f"{name}.xml")
        r = gi.Renderer(scene, "path", size=(64, 64), spp=256, seed=7)
    img = r.render().radiance[..., :3]
    ref = gi.read_image(SCENES / f"{name}-reference.exr")[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
    error = flip(ref, img)
    assert np.all(np.abs(ratio - 1) <= 0.02), f"{name}: ratio per channel {ratio}"
    assert error <= 0.05, f"{name}: FLIP {error:.4f}"
    # Where the light is, not only how much: every 8×8 block's mean within 7% per channel
    # (measured at most 3.4%, the noise of the rough glass's caustic; 1.1% elsewhere). The
    # caustic was 12–25% dark while the image mean was 0.983 (light samples refused across
    # rough glass, issue 42).
    blocks = img.reshape(8, 8, 8, 8, 3).mean((1, 3)) / ref.reshape(8, 8, 8, 8, 3).mean((1, 3))
    worst = np.abs(blocks - 1).max()
    assert worst <= 0.07, f"{name}: an 8x8 block off by {worst:.3f}"


@pytest.mark.parametrize(
    "name, method",
    [(name, "ispm") for name in NAMES] + [("conductor-au", "bidir"), ("plastic", "bidir")],
)
def test_gpu_methods_match_mitsuba(name, method):
    """`ispm` on every sphere, `bidir` on the smooth ones (the sky and the area light seen in
    their mirror lobe come from the CPU specular image; before it added them, 0.50–0.73 and
    0.93–0.95): the image mean within 5% of Mitsuba's per channel (issue 42; measured within
    3.5% with the uber stand-ins, within 0.8% with the exact models;
    docs/bench/materials.md). `ispm` renders the rough glass with its own lobes: its
    specular image follows camera paths through them and lights where they land by every
    source (measured 0.992; 0.85 with the smooth stand-in and the landings lit by the point
    lights alone, the floor seen through the sphere at 0.15 of Mitsuba's)."""
    scene = gi.load_scene(SCENES / f"{name}.xml")
    settings = {"ispm": {"photons": 100_000, "spp": 8}, "bidir": {"spp": 8}}[method]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gi.RenderWarning)  # the stand-ins, tested below
        r = gi.Renderer(scene, method, size=(64, 64), seed=7, **settings)
    img = r.render().radiance[..., :3]
    ref = gi.read_image(SCENES / f"{name}-reference.exr")[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
    assert np.all(np.abs(ratio - 1) <= 0.05), f"{name} {method}: ratio per channel {ratio}"


@pytest.mark.parametrize("method", ["photon", "gather"])
def test_photon_methods_render_rough_glass(method):
    """`photon` and `gather` scatter photons and camera paths through the rough glass with
    the CPU BSDF (photons with its adjoint): the image mean within 3% of Mitsuba's per
    channel, issue 42's bound for these methods (measured 1.001 and 0.990 at these
    settings, docs/bench/materials.md; before, photons stored on the inside of the glass
    lit the floor beneath it 2× and camera paths stopped after 8 scatterings in the glass,
    7% dark at the rim: 1.047 and 1.021)."""
    scene = gi.load_scene(SCENES / "roughdielectric.xml")
    r = gi.Renderer(scene, method, size=(64, 64), spp=16, photons=200_000, seed=7)
    img = r.render().radiance[..., :3]
    ref = gi.read_image(SCENES / "roughdielectric-reference.exr")[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
    assert np.all(np.abs(ratio - 1) <= 0.03), f"{method}: ratio per channel {ratio}"


ROUGH = ["roughconductor-al-ggx", "roughconductor-cu", "roughplastic-beckmann", "roughplastic-ggx"]


@pytest.mark.parametrize("method", ["direct", "ispm", "bidir"])
@pytest.mark.parametrize("name", ROUGH)
def test_gpu_direct_light_shades_the_exact_models(name, method):
    """`direct`, `ispm` and `bidir` on the rough spheres: a convex sphere under a constant sky
    and an area light receives direct light only, and its lobes are all non-delta, so the
    GPU direct light (in `bidir`: the area light's, and the sky's through the ray bundles'
    misses, bidir.wgsl) is the whole of Mitsuba's image. With the uber stand-ins (before the
    G-buffer carried the exact models), `direct` at these settings: Cu (Beckmann)
    0.978-0.982 of Mitsuba's mean, FLIP 0.058; Al 1.011-1.012, FLIP 0.034; nonlinear
    Beckmann plastic 0.992-0.996, FLIP 0.045; GGX plastic 0.999, FLIP 0.026 (it passed
    already). With the exact models all within 0.8%, FLIP ≤ 0.030 (docs/bench/materials.md).
    `bidir` with the stand-ins at its pixels (before bidir_models.wgsl): Cu 0.977-0.981,
    FLIP 0.057; Al 1.011-1.012, FLIP 0.033; Beckmann plastic 0.990-0.995, FLIP 0.051; GGX
    plastic 0.996-0.998, FLIP 0.036, and a RenderWarning (none since its VPLs and bundle
    hits shade the models too). Tolerances 1% and FLIP
    0.035: the tessellated silhouette, the area light's 16 shadow-mapped points, the sky's
    16-tap glossy quadrature, 16 spp of noise."""
    scene = gi.load_scene(SCENES / f"{name}.xml")
    settings = {
        "direct": {"spp": 16},
        "ispm": {"spp": 16, "photons": 100_000},
        "bidir": {"spp": 16},
    }[method]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing approximated: no stand-in warning
        r = gi.Renderer(scene, method, size=(64, 64), seed=7, **settings)
    img = r.render().radiance[..., :3]
    ref = gi.read_image(SCENES / f"{name}-reference.exr")[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
    error = flip(ref, img)
    assert np.all(np.abs(ratio - 1) <= 0.01), f"{name} {method}: ratio per channel {ratio}"
    assert error <= 0.035, f"{name} {method}: FLIP {error:.4f}"


@pytest.mark.parametrize("name", NAMES)
def test_direct_matches_mitsubas_direct(name):
    """`direct` against Mitsuba's `direct` integrator (references.json's "direct": one
    emitter and one BSDF sample per sample at the first hit, 1024 spp, standard error under
    0.04%), which counts the light its BSDF sample finds through a delta lobe (the sky and
    the area light in the gold mirror and in the plastic's smooth coating, Fresnel-weighted)
    and the rough glass's own lobes. gi's GPU direct light shades the non-delta lobes; the
    rest is traced on the CPU (photon/delta_light.rs). Before, none of it: conductor-au
    0.50-0.73 of Mitsuba's `direct` mean (FLIP 0.557), plastic 0.925-0.947 (0.229),
    roughdielectric 0.928 (0.347; the sphere rendered as smooth glass, black). Measured now
    (seeds 1-3 and 7): within 0.25% on the smooth spheres and the glass, 0.5% on the rough
    ones; FLIP 0.008-0.016 on the smooth spheres, 0.144-0.149 on the glass (its highlight
    BSDF-sampled at 16 spp: 0.098 at 64 spp, 0.070 at 256).
    Tolerances: the mean within 2% (the tessellated silhouette, the shadow-mapped area light
    and the sky's glossy taps: 0.8% at most on the rough spheres in
    test_gpu_direct_light_shades_the_exact_models; the highlight's noise, 0.25% over seeds;
    before, 7-50% off); FLIP 0.035 (as the rough spheres' test), 0.2 on the glass (0.347
    before). Mitsuba's `direct` image is its `path` image on a lone sphere (convex, under a
    sky: no light arrives after two bounces; the means agree to 0.05%), committed apart for
    the glass on its floor."""
    scene = gi.load_scene(SCENES / f"{name}.xml")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing approximated: no stand-in warning
        r = gi.Renderer(scene, "direct", size=(64, 64), seed=7, spp=16)
    img = r.render().radiance[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / np.array(META[name]["direct"]["mean"])
    assert np.all(np.abs(ratio - 1) <= 0.02), f"{name}: ratio per channel {ratio}"
    own = SCENES / f"{name}-direct-reference.exr"
    ref = gi.read_image(own if own.exists() else SCENES / f"{name}-reference.exr")[..., :3]
    error = flip(ref, img)
    assert error <= (0.2 if name == "roughdielectric" else 0.035), f"{name}: FLIP {error:.4f}"


INDIRECT_SCENE = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world">
            <lookat origin="0, 2.5, 5" target="0, -0.5, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="48"/><integer name="height" value="48"/>
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.5"/><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="20"/></emitter>
    </shape>
    <shape type="sphere">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.6, 0.4"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="4"/><rotate x="1" angle="-90"/><translate y="-1"/>
        </transform>
        FLOOR
    </shape>
</scene>
"""


def point_lit(xml: str) -> str:
    """`xml` with its area light replaced by a point light above the sphere (the bounce
    maps of `first_bounce` "raster" are the point and spot lights')."""
    start = xml.index('    <shape type="rectangle">')
    end = xml.index("    </shape>", start) + len("    </shape>\n")
    point = (
        '    <emitter type="point"><point name="position" x="0.5" y="3" z="0.5"/>'
        '<rgb name="intensity" value="20"/></emitter>\n'
    )
    return xml[:start] + point + xml[end:]


FLOORS = {
    "roughplastic-beckmann": '<bsdf type="roughplastic"><boolean name="nonlinear" value="true"/>'
    '<rgb name="diffuse_reflectance" value="0.8, 0.7, 0.2"/></bsdf>',
    "roughconductor-cu": '<bsdf type="roughconductor"><string name="material" value="Cu"/>'
    '<float name="alpha" value="0.2"/></bsdf>',
}


@pytest.mark.parametrize("floor", sorted(FLOORS))
def test_ispm_estimators_shade_the_exact_models(tmp_path, floor):
    """The photon estimates of `ispm` at a Mitsuba model (a floor lit by the light a diffuse
    sphere reflects): the GPU estimators (`volumes`, `tiled`, `cluster`: models.wgsl through
    the G-buffer's material index) equal the CPU estimator, which evaluates the CPU's
    `Material` itself (matched to Mitsuba to 1e-3 in crates/core/src/bsdf/tests_models.rs),
    to 1e-4 of the image's peak, as the estimators agree on uber materials
    (test_api.py); measured 3e-6 (Cu) and 6e-7 (plastic). The uber stand-ins' estimate
    (before the estimators read the G-buffer's material index) differs from the exact one by
    26% (Cu: its mean 19% low) and 0.7% (plastic) of the peak."""
    path = tmp_path / "floor.xml"
    path.write_text(INDIRECT_SCENE.replace("FLOOR", FLOORS[floor]))
    scene = gi.load_scene(path)
    images = {}
    for est in ("volumes", "tiled", "cluster", "cpu"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no stand-in left
            r = gi.render(
                scene, "ispm", spp=1, photons=20_000, estimator=est, first_bounce="traced"
            )
        images[est] = r.aov("indirect")
    scale = images["cpu"].max()
    assert scale > 0
    for est in ("volumes", "tiled", "cluster"):
        np.testing.assert_allclose(images[est], images["cpu"], rtol=0, atol=1e-4 * scale)


def test_gpu_methods_name_their_stand_ins():
    scene = gi.load_scene(SCENES / "plastic.xml")
    for method in ["direct", "ispm", "bidir"]:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # they shade the exact model (`bidir`: everywhere)
            gi.Renderer(scene, method, size=(16, 16))
    glass = gi.load_scene(SCENES / "roughdielectric.xml")
    with pytest.warns(gi.RenderWarning, match="smooth glass"):
        gi.Renderer(glass, "bidir", size=(16, 16))
    for method in ["direct", "ispm"]:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # they render the rough lobes: no stand-in
            gi.Renderer(glass, method, size=(16, 16))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gi.Renderer(scene, "path", size=(16, 16), spp=1)


@pytest.mark.parametrize(
    "bsdf, element",
    [
        (
            '<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/>'
            '<float name="alpha_v" value="0.2"/></bsdf>',
            '<bsdf type="roughplastic">',
        ),
        (
            '<bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf>',
            '<string name="distribution">',
        ),
        (
            '<bsdf type="conductor"><string name="material" value="Au"/>'
            '<rgb name="eta" value="0.2"/></bsdf>',
            '<string name="material">',
        ),
        (
            '<bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf>',
            '<string name="material">',
        ),
        (
            '<bsdf type="plastic"><float name="int_ior" value="1.2"/>'
            '<float name="ext_ior" value="1.33"/></bsdf>',
            '<bsdf type="plastic">',
        ),
        (
            '<bsdf type="roughdielectric"><float name="alpha_u" value="0.1"/>'
            '<float name="alpha_v" value="0.3"/></bsdf>',
            '<float name="alpha_u">',
        ),
        (
            '<bsdf type="roughdielectric"><float name="int_ior" value="1.0"/>'
            '<float name="ext_ior" value="1.33"/></bsdf>',
            '<bsdf type="roughdielectric">',
        ),
        (
            '<bsdf type="roughdielectric"><string name="distribution" value="phong"/></bsdf>',
            '<string name="distribution">',
        ),
    ],
)
def test_material_properties_gi_cannot_render_are_errors(tmp_path, bsdf, element):
    """Mitsuba refuses these too (or they have no meaning): a SceneError naming the file,
    the element and its line, never a warning and another material."""
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n<shape type="sphere">\n{bsdf}\n</shape>\n</scene>\n')
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.field == f"{element} (line 3)", e.value.field
    assert e.value.file.endswith("s.xml")


def test_progressive_ispm_renders_rough_glass():
    """Progressive `ispm` traces the first surface's direct light on the CPU; on rough glass
    it leaves it to the specular image, whose camera paths follow the glass's lobes and meet
    that light (counted once): the image mean within 5% of Mitsuba's (issue 42's bound for
    ispm; measured 1.016 at these settings)."""
    scene = gi.load_scene(SCENES / "roughdielectric.xml")
    r = gi.Renderer(
        scene, "ispm", size=(64, 64), seed=7, photons=50_000, spp=4, subsample=1, progressive=True
    )
    img = r.render_progressive(passes=6).radiance[..., :3]
    ref = gi.read_image(SCENES / "roughdielectric-reference.exr")[..., :3]
    ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
    assert np.all(np.abs(ratio - 1) <= 0.05), f"ratio per channel {ratio}"
