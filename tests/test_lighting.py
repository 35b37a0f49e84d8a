"""Lighting a scene from outside it (`gi.lighting`): ``environment=`` in gi.render and
gi.Renderer, Renderer.update(environment=), ``gi render --env``, the built-in sky, adding
to or replacing the scene's light, and the one message for a scene without light.

The reference is analytic: a convex diffuse object under a constant sky L has radiance
albedo × L everywhere (it sees only the sky), and pixels that miss show the sky exactly."""

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from gltf_assets import normal_mapped_quad

import gi
from gi import lighting

RHO = 0.5


def sphere_scene(write_scene, lights=(), environment=None):
    desc = {
        "camera": {
            "position": [0, 0, 4],
            "look_at": [0, 0, 0],
            "fov": 40,
            "width": 32,
            "height": 32,
        },
        "lights": list(lights),
        "materials": {"m": {"diffuse": [RHO] * 3}},
        "objects": [{"shape": {"type": "sphere", "radius": 1}, "material": "m"}],
    }
    if environment is not None:
        desc["environment"] = environment
    return gi.load_scene(write_scene(desc))


def masks(result):
    """Pixels wholly on the object and wholly off it (the edge pixels, partly both, and
    their neighbours left out)."""
    depth = result.depth if result.depth.ndim == 2 else result.depth[..., 0]
    hit = depth > 0
    pad = np.pad(hit, 1, mode="edge")
    near = [
        pad[1 + dy : pad.shape[0] - 1 + dy, 1 + dx : pad.shape[1] - 1 + dx]
        for dy in (-1, 0, 1)
        for dx in (-1, 0, 1)
    ]
    return np.logical_and.reduce(near), ~np.logical_or.reduce(near)


def test_constant_environment_array_lights_a_convex_object_exactly(write_scene):
    """An (H, W, 3) array of 0.5 at strength 2 is a sky of 1: the sphere shows ρ·1 and the
    background 1 (path, 64 spp: the estimator is exact for a constant sky up to MIS noise,
    mean within 1%)."""
    with pytest.warns(gi.SceneWarning, match="--env"):
        bare = sphere_scene(write_scene)
        gi.Renderer(bare, "path", spp=1)
    env = {"source": np.full((8, 16, 3), 0.5, np.float32), "strength": 2.0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # lit: no warning
        r = gi.render(bare, "path", spp=64, seed=1, environment=env)
    hit, miss = masks(r)
    np.testing.assert_allclose(r.radiance[miss], 1.0, rtol=1e-6)
    assert r.radiance[hit].mean() == pytest.approx(RHO, rel=0.01)


def test_add_sums_with_the_scenes_own_sky_and_keeps_its_lights(write_scene):
    light = {"type": "point", "position": [0, 3, 0], "intensity": [2, 2, 2]}
    scene = sphere_scene(write_scene, [light], {"radiance": [0.25, 0.25, 0.25]})
    added = lighting.with_environment(scene, np.full((4, 8, 3), 0.5, np.float32))
    assert added.light_count == 1 and added.has_environment
    r = gi.render(added, "path", spp=4, seed=1)
    _, miss = masks(r)
    np.testing.assert_allclose(r.radiance[miss], 0.75, rtol=1e-6)
    replaced = lighting.with_environment(
        scene, {"source": np.full((4, 8, 3), 0.5, np.float32), "mode": "replace"}
    )
    assert replaced.light_count == 0
    r = gi.render(replaced, "path", spp=64, seed=1)
    hit, miss = masks(r)
    np.testing.assert_allclose(r.radiance[miss], 0.5, rtol=1e-6)
    assert r.radiance[hit].mean() == pytest.approx(RHO * 0.5, rel=0.01)


def test_renderer_update_changes_the_environment_and_none_restores_the_scene(write_scene):
    scene = sphere_scene(write_scene, environment={"radiance": [0.2, 0.2, 0.2]})
    r = gi.Renderer(scene, "path", spp=4, seed=5)
    before = r.render().radiance
    r.update(environment={"source": np.full((4, 8, 3), 1.0, np.float32), "mode": "replace"})
    lit = r.render().radiance
    hit, miss = masks(gi.render(scene, "path", spp=1))
    np.testing.assert_allclose(lit[miss], 1.0, rtol=1e-6)
    # Calls do not accumulate: "add" twice is the scene's sky plus one.
    for _ in range(2):
        r.update(environment={"source": np.full((4, 8, 3), 1.0, np.float32)})
    np.testing.assert_allclose(r.render().radiance[miss], 1.2, rtol=1e-6)
    r.update(environment="none")
    np.testing.assert_array_equal(r.render().radiance, before)


def gradient_sky(top, bottom):
    """A 8×16 equirectangular sky from ``top`` at the zenith to ``bottom`` at the nadir."""
    t = np.linspace(0, 1, 8, dtype=np.float32)[:, None, None]
    rows = (1 - t) * np.float32(top) + t * np.float32(bottom)
    return np.repeat(rows, 16, axis=1).astype(np.float32)


def created(after, before):
    return {k: after[k] - before[k] for k in ("buffers", "textures", "bind_groups", "pipelines")}


@pytest.mark.parametrize("method", ["direct", "ispm", "bidir"])
def test_environment_update_keeps_the_gpu_scene_and_renders_as_a_new_renderer(write_scene, method):
    """A GPU renderer's Renderer.update(environment=) swaps the environment's tables only.
    Between the frames before and after it: no pipeline and no buffer is created for
    `direct` and `ispm`, only the two environment tables and the bind group that holds them
    (`bidir` makes its own state anew: fewer objects than a new renderer's first frame), and
    the scene's texture table is not uploaded again. The image is the image of a new
    Renderer made with that environment (same seed; measured equal to the bit)."""
    scene = sphere_scene(write_scene, environment={"radiance": [0.2, 0.2, 0.2]})
    opts = {"spp": 2, "seed": 3}
    if method == "ispm":
        opts["photons"] = 2000
    if method == "bidir":
        opts["bundles"] = 4
    sky = {"source": gradient_sky([1.5, 1.2, 1.0], [0.1, 0.1, 0.2]), "mode": "replace"}
    start = gi.gpu_counters()
    fresh = gi.Renderer(scene, method, environment=sky, **opts).render().radiance
    new_renderer = created(gi.gpu_counters(), start)
    r = gi.Renderer(scene, method, **opts)
    r.render()
    r.render()
    before = gi.gpu_counters()
    r.update(environment=sky)
    updated = r.render().radiance
    after = gi.gpu_counters()
    made = created(after, before)
    assert made["pipelines"] == 0
    if method == "bidir":
        for kind in ("buffers", "textures", "bind_groups"):
            assert made[kind] < new_renderer[kind], (kind, made, new_renderer)
    else:
        assert made == {"buffers": 0, "textures": 2, "bind_groups": 1, "pipelines": 0}
    labels = {label for label, _ in after["uploads"][len(before["uploads"]) :]}
    assert {"environment radiance", "environment irradiance"} <= labels
    assert "texture table" not in labels, labels
    np.testing.assert_allclose(updated, fresh, rtol=0, atol=1e-6)


def test_built_in_sky_has_a_sun_that_strength_and_rotation_move(write_scene):
    scene = sphere_scene(write_scene)
    lit = lighting.with_environment(scene, "sky")
    assert lit.light_count == 1 and lit.has_environment
    sky = lighting.Lighting({"source": "sky", "strength": 2, "sun": [1, 1, 0]})
    sun = sky.lights[0]
    np.testing.assert_allclose(sun["direction"], [-(0.5**0.5), -(0.5**0.5), 0], atol=1e-12)
    np.testing.assert_allclose(sun["irradiance"], [2 * e for e in lighting.SUN_IRRADIANCE])
    assert lighting.Lighting({"source": "sky", "sun": None}).lights == []
    # The sky's brightest horizon column faces the sun, whatever the rotation.
    for rotation in (0.0, 90.0):
        spec = {"source": "sky", "sun": [1, 0.2, 0], "rotation": rotation}
        img = lighting.Lighting(spec).image
        col = int(np.argmax(img[img.shape[0] // 2 - 1, :, 0]))
        phi = 2 * np.pi * (col + 0.5) / img.shape[1]
        local = np.array([np.sin(phi), 0.0, -np.cos(phi)])
        r = np.radians(rotation)
        world = [
            np.cos(r) * local[0] + np.sin(r) * local[2],
            0,
            -np.sin(r) * local[0] + np.cos(r) * local[2],
        ]
        assert world[0] > 0.98, (rotation, world)


@pytest.mark.parametrize(
    ("spec", "field"),
    [
        ({"source": "sky", "sun": [0, -1, 0]}, "environment.sun"),
        ({"source": "sky", "strength": -1}, "environment.strength"),
        ({"source": "sky", "mode": "merge"}, "environment.mode"),
        ({"source": "sky", "colour": 1}, "environment.colour"),
        ({"source": np.zeros((4, 8, 2))}, "environment"),
        ({"source": "missing.hdr"}, "environment.source"),
    ],
)
def test_bad_environments_are_typed_errors_naming_the_field(spec, field):
    with pytest.raises((gi.SettingError, gi.SceneError)) as e:
        lighting.Lighting(spec)
    assert field in str(e.value)


def test_gltf_without_lights_warns_nearly_black_and_env_lights_it(tmp_path):
    """A glTF asset with no lights (lit by the viewer's environment in every glTF viewer):
    the message names --env; with the built-in sky it renders lit, every GPU method within
    5% of `path`'s mean."""
    with pytest.warns(gi.SceneWarning, match="the image is black.*--env"):
        gi.Renderer(gi.load_scene(normal_mapped_quad(tmp_path / "bare.glb")), "path", spp=1)
    glb = normal_mapped_quad(tmp_path / "asset.glb", emissive=0.05)
    scene = gi.load_scene(glb)
    with pytest.warns(gi.SceneWarning, match="nearly black.*--env"):
        gi.Renderer(scene, "path", spp=1)
    lit = lighting.with_environment(scene, "sky")
    means = {}
    for method, kw in (("path", {"spp": 64}), ("direct", {"spp": 4}), ("ispm", {"spp": 4})):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            r = gi.render(lit, method, size=(32, 32), seed=1, **kw)
        means[method] = float(r.radiance.mean())
    assert means["path"] > 0.5
    for method in ("direct", "ispm"):
        assert means[method] == pytest.approx(means["path"], rel=0.05), means


def test_cli_env_sky_renders_a_lit_asset(tmp_path):
    glb = normal_mapped_quad(tmp_path / "asset.glb", emissive=0.05)
    out = tmp_path / "out.exr"
    cmd = [sys.executable, "-m", "gi.cli", "render", str(glb), "--method", "path", "--size"]
    cmd += ["32x32", "--spp", "4", "-q", "-o", str(out)]
    bare = subprocess.run(cmd, capture_output=True, text=True)
    assert bare.returncode == 0, bare.stderr
    assert "nearly black" in bare.stderr and "--env" in bare.stderr
    lit = subprocess.run([*cmd, "--env", "sky", "--sun", "1,1,1"], capture_output=True, text=True)
    assert lit.returncode == 0 and "nearly black" not in lit.stderr, lit.stderr
    hdr = Path(__file__).parents[1] / "docs" / "examples" / "sky" / "sky.exr"
    image = [*cmd, "--env", str(hdr), "--env-strength", "2", "--env-rotation", "90"]
    lit = subprocess.run(image, capture_output=True, text=True)
    assert lit.returncode == 0 and "nearly black" not in lit.stderr, lit.stderr
    assert gi.read_image(out).mean() > 0.1
    bad = subprocess.run([*cmd, "--sun", "1,1,1"], capture_output=True, text=True)
    assert bad.returncode != 0 and "--env sky" in bad.stderr


def test_viewer_environment_message_is_an_update():
    from gi.viewer import messages as m

    msg = m.parse(json.dumps({"type": "environment", "source": "sky", "strength": 2}), ["path"])
    assert msg.spec() == {"source": "sky", "strength": 2.0, "rotation": 0.0, "mode": "add"}
    assert m.parse('{"type": "environment", "source": "scene"}', ["path"]).spec() == "none"
    with pytest.raises(m.MessageError):
        m.parse('{"type": "environment", "source": "/etc/passwd"}', ["path"])


def test_viewer_panel_lights_a_gltf_asset_and_gives_the_scene_back(tmp_path):
    """The Environment panel's choice reaches the renderer (the sky lights the unlit asset),
    a change of method keeps it (the progressive renderer too), and "scene" restores the
    file's own (black) light."""
    from gi.viewer import messages as m
    from gi.viewer.engine import Engine

    scene = gi.load_scene(normal_mapped_quad(tmp_path / "asset.glb", emissive=0.05))
    with pytest.warns(gi.SceneWarning, match="nearly black"):
        engine = Engine(
            scene,
            "direct",
            {"size": (16, 16), "spp": 1},
            on_frame=lambda frame: None,
            on_event=lambda client, event: None,
        )
    engine.start()
    try:

        def send(msg):
            return engine.submit(msg, 1, wait=True).result(timeout=120)

        def mean():
            frame = engine.wait_frame(timeout=120)
            assert frame is not None
            return float(frame.pixels.astype(np.float64).mean())

        dark = mean()
        send(m.Environment("sky", strength=1.0))
        assert engine.state()["environment"]["source"] == "sky"
        lit = mean()
        assert lit > dark + 50  # 8-bit sRGB pixels: a lit quad, not a black image
        # A new renderer starts from the unlit scene (and says so) before the panel's sky.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", gi.SceneWarning)
            send(m.Settings({"method": "path"}))
        assert mean() > dark + 50
        send(m.Environment("scene"))
        assert mean() == pytest.approx(dark, abs=5)
    finally:
        engine.stop()
