"""gi.Renderer: the persistent frame engine from Python."""

import numpy as np
import pytest

import gi

SMALL = {"size": (32, 24), "spp": 4, "photons": 4000, "k": 16, "max_depth": 4}


@pytest.fixture(scope="module")
def cornell() -> gi.Scene:
    return gi.load_scene("cornell")


@pytest.mark.parametrize("method", gi.methods())
def test_frame_equals_one_shot(cornell: gi.Scene, method: str) -> None:
    """A renderer's frame after an update and its undo equals gi.render of the scene (every
    method is deterministic for a seed)."""
    r = gi.Renderer(cornell, method, **gi.method_options(method, **SMALL))
    r.render()
    light = r.describe("light", 0)
    r.update(lights={0: {"intensity": [1.0, 1.0, 1.0]}})
    r.render()
    r.update(lights={0: light})
    frame = r.render(aovs=True, extras=True)
    one_shot = gi.render(cornell, method, **gi.method_options(method, **SMALL))
    np.testing.assert_array_equal(frame.radiance, one_shot.radiance)
    np.testing.assert_array_equal(frame.albedo, one_shot.albedo)
    assert sorted(frame.extra) == sorted(one_shot.extra)
    assert r.frame_index == 3


def test_only_requested_images_are_returned(cornell: gi.Scene) -> None:
    r = gi.Renderer(cornell, "direct", **gi.method_options("direct", **SMALL))
    frame = r.render()
    assert frame.radiance.shape == (24, 32, 3)
    assert frame.albedo.size == 0 and frame.depth.size == 0 and frame.extra == {}
    frame = r.render(aovs=True)
    assert frame.albedo.shape == (24, 32, 3) and frame.depth.shape == (24, 32)


def test_steady_state_creates_no_gpu_objects(cornell: gi.Scene) -> None:
    r = gi.Renderer(cornell, "ispm", **SMALL)
    estimator = r.render().stats.estimator
    before = gi.gpu_counters()
    r.render()
    r.update(camera={"position": [0.1, 1.0, 3.4]})
    r.render()
    after = gi.gpu_counters()
    for kind in ("buffers", "textures", "bind_groups", "pipelines"):
        assert after[kind] == before[kind], kind
    labels = {label for label, _ in after["uploads"][len(before["uploads"]) :]}
    # A camera move re-sorts the raster volumes' photons (small ones as quads); the compute
    # estimators keep theirs and update their parameters; the CPU estimate (CPU devices)
    # uploads the new estimate.
    if estimator == "volumes":
        assert labels == {"eye views", "photons", "volume params", "upsample params"}
    elif estimator == "cpu":
        assert labels == {"eye views", "cpu estimate", "upsample params"}
    else:
        assert labels == {"eye views", "tiled params", "upsample params"}


def test_moving_an_object_and_a_material(cornell: gi.Scene) -> None:
    r = gi.Renderer(cornell, "direct", **gi.method_options("direct", **SMALL))
    still = r.render().radiance
    r.update(objects={len(r.object_names) - 1: {"translate": [0.3, 0.0, 0.0]}})
    moved = r.render().radiance
    assert np.abs(moved - still).max() > 0.05
    name = gi.load_scene("cornell").material_names[0]
    r.update(materials={name: {"diffuse": [0.1, 0.1, 0.1]}})
    assert np.abs(r.render().radiance - moved).max() > 0.01
    assert r.describe("material", name)["diffuse"] == pytest.approx([0.1, 0.1, 0.1])


def test_resize(cornell: gi.Scene) -> None:
    r = gi.Renderer(cornell, "ispm", **SMALL)
    r.render()
    r.resize(20, 10)
    assert r.size == (20, 10)
    assert r.render().radiance.shape == (10, 20, 3)


@pytest.mark.parametrize(
    ("update", "field"),
    [
        ({"lights": {0: {"intensity": [1, "x", 1]}}}, "lights[0].intensity"),
        ({"lights": {5: {"intensity": [1, 1, 1]}}}, "lights[5]"),
        ({"camera": {"fov": 500}}, "camera.fov"),
        ({"objects": {"nope": {"translate": [0, 0, 0]}}}, "objects"),
        ({"objects": {0: {"scale": 0}}}, "objects[0].transform.scale"),
        ({"materials": {"nope": {"roughness": 0.5}}}, "materials.nope"),
    ],
)
def test_bad_updates_are_scene_errors(cornell: gi.Scene, update: dict, field: str) -> None:
    r = gi.Renderer(cornell, "direct", **gi.method_options("direct", **SMALL))
    with pytest.raises(gi.SceneError) as e:
        r.update(**update)
    assert e.value.field == field  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("settings", "name"),
    [
        ({"spp": -1}, "spp"),
        ({"seed": 2**64}, "seed"),
        ({"photons": -1}, "photons"),
        ({"kernel_scale": float("nan")}, "kernel_scale"),
        ({"temporal_frames": 0}, "temporal_frames"),
        ({"spp": True}, "spp"),
        ({"colour": 1}, "settings"),
    ],
)
def test_bad_settings_name_the_setting(cornell: gi.Scene, settings: dict, name: str) -> None:
    with pytest.raises(gi.SettingError) as e:
        gi.Renderer(cornell, "ispm", **settings)
    assert e.value.setting == name  # type: ignore[attr-defined]


def test_temporal_reuse_varies_the_photons_per_frame(cornell: gi.Scene) -> None:
    """With temporal_frames > 1 each frame traces new photons (another seed) and keeps the
    last ones: the stored photon count grows until the ring is full."""
    r = gi.Renderer(cornell, "ispm", temporal_frames=3, **SMALL)
    counts = [r.render().stats.photons_stored for _ in range(4)]
    assert counts[1] > 1.5 * counts[0]
    assert counts[2] > 2.5 * counts[0]
    assert counts[3] == pytest.approx(counts[2], rel=0.1)
