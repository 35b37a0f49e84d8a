"""Bad input gets a typed exception naming the file and field; nothing panics or hangs."""

import json

import numpy as np
import pytest

import gi


def scene_error(path_or_name):
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path_or_name)
    return e.value


def test_missing_file_and_unknown_builtin(tmp_path):
    e = scene_error(tmp_path / "nope.json")
    assert e.file.endswith("nope.json") and "no such scene file" in str(e)
    e = scene_error("not-a-scene")
    assert "built-in scenes" in str(e)


def test_invalid_json(write_scene):
    e = scene_error(write_scene('{"camera": {'))
    assert "invalid JSON" in str(e) and "line 1" in e.field


def test_unknown_field(write_scene, cornell_desc):
    cornell_desc["objects"][2]["colour"] = [1, 0, 0]
    e = scene_error(write_scene(cornell_desc))
    assert e.field == "objects[2].colour" and "unknown field" in e.reason


def test_unknown_material_name(write_scene, cornell_desc):
    cornell_desc["objects"][1]["material"] = "chrome"
    e = scene_error(write_scene(cornell_desc))
    assert e.field == "objects[1].material" and "chrome" in e.reason


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d["camera"].update(look_at=d["camera"]["position"]), "camera.look_at"),
        (lambda d: d["camera"].update(up=[0, 0, -1]), "camera.up"),
        (lambda d: d["camera"].update(fov=0), "camera.fov"),
        (lambda d: d["camera"].update(width=0), "camera.width"),
        (lambda d: d["lights"][0].update(intensity=[1, -1, 1]), "lights[0].intensity"),
        (lambda d: d["materials"]["white"].update(diffuse=[1.5, 0, 0]), "materials.white.diffuse"),
        (
            lambda d: d["materials"]["white"].update(transmission=[0.5, 0.5, 0.5]),
            "materials.white.transmission",
        ),
        (lambda d: d["objects"][0]["transform"].update(scale=0), "objects[0].transform.scale"),
        (lambda d: d["objects"][0]["shape"].update(size=[-1, 1]), "objects[0].shape.size"),
    ],
)
def test_invalid_values_name_the_field(write_scene, cornell_desc, edit, field):
    cornell_desc["objects"][0].setdefault("transform", {})
    edit(cornell_desc)
    e = scene_error(write_scene(cornell_desc))
    assert e.field == field, str(e)


def test_camera_straight_up_is_degenerate(write_scene, cornell_desc):
    cornell_desc["camera"].update(position=[0, 0, 0], look_at=[0, 5, 0], up=[0, 1, 0])
    assert scene_error(write_scene(cornell_desc)).field == "camera.up"


def test_missing_mesh_file(write_scene, cornell_desc):
    cornell_desc["objects"].append(
        {"shape": {"type": "mesh", "file": "gone.obj"}, "material": "white"}
    )
    e = scene_error(write_scene(cornell_desc))
    assert e.field == "objects[7].shape.file" and "not found" in e.reason


def test_unreadable_mesh_file(write_scene, cornell_desc, tmp_path):
    (tmp_path / "junk.ply").write_bytes(b"ply\nformat nonsense\n\x00\x01")
    cornell_desc["objects"].append(
        {"shape": {"type": "mesh", "file": "junk.ply"}, "material": "white"}
    )
    e = scene_error(write_scene(cornell_desc))
    assert e.field == "objects[7].shape.file"


def test_nan_vertices_in_mesh_file(write_scene, cornell_desc, tmp_path):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    cornell_desc["objects"].append(
        {"shape": {"type": "mesh", "file": "nan.obj"}, "material": "white"}
    )
    e = scene_error(write_scene(cornell_desc))
    assert "not finite" in str(e)


def test_nan_geometry_through_arrays(cornell_desc):
    cornell_desc["objects"].append({"shape": {"type": "mesh", "file": "m"}, "material": "white"})
    v = np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], np.float32)
    f = np.array([[0, 1, 2]], np.uint32)
    with pytest.raises(gi.SceneError) as e:
        gi.Scene.from_json(json.dumps(cornell_desc), "arrays", {"m": (v, f, None, None, None)})
    assert e.value.field == "objects[7].shape" and "not finite" in str(e.value)
    bad_index = np.array([[0, 1, 7]], np.uint32)
    with pytest.raises(gi.SceneError, match="out of range"):
        gi.Scene.from_json(
            json.dumps(cornell_desc),
            "arrays",
            {"m": (np.zeros_like(v), bad_index, None, None, None)},
        )


def test_nan_in_description(write_scene, cornell_desc):
    text = json.dumps(cornell_desc).replace('"fov": 40', '"fov": NaN')
    assert scene_error(write_scene(text)).field == "camera.fov"


@pytest.mark.parametrize(
    ("kwargs", "setting"),
    [
        ({"method": "path", "spp": 0}, "spp"),
        ({"method": "path", "spp": 10**9}, "spp"),
        ({"method": "path", "size": (0, 10)}, "width"),
        ({"method": "path", "max_depth": 0}, "max_depth"),
        ({"method": "path", "light_paths": 10**15}, "light_paths"),
        ({"method": "magic"}, "method"),
        ({"method": "photon", "photons": 0}, "photons"),
        ({"method": "photon", "photons": 10**12}, "photons"),
        ({"method": "photon", "kernel": "gaussian"}, "kernel"),
        ({"method": "gather", "smoothing": 0.0}, "smoothing"),
        ({"method": "gather", "leaf_size": 0}, "leaf_size"),
        ({"method": "ispm", "subsample": 9}, "subsample"),
        ({"method": "ispm", "kernel_scale": -1.0}, "kernel_scale"),
        ({"method": "ispm", "volume_shape": "sphere"}, "volume_shape"),
    ],
)
def test_absurd_settings(kwargs, setting):
    scene = gi.load_scene("cornell")
    with pytest.raises(gi.SettingError) as e:
        gi.render(scene, **kwargs)
    assert e.value.setting == setting


def test_errors_share_a_base_class():
    for cls in (gi.SceneError, gi.SettingError, gi.GpuError, gi.RenderCancelled):
        assert issubclass(cls, gi.GiError)
