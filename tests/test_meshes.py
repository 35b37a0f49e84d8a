"""Mesh files of every supported format load through trimesh and render."""

import json

import numpy as np
import pytest
import trimesh

import gi


def scene_with_mesh(tmp_path, filename, material=True):
    desc = json.loads(gi.builtin_json("cornell"))
    obj = {"shape": {"type": "mesh", "file": filename}, "transform": {"translate": [0, 0.5, 0]}}
    if material:
        obj["material"] = "white"
    desc["objects"] = desc["objects"][:5] + [obj]
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(desc))
    return path


@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "glb"])
def test_formats_load_with_the_right_triangle_count(tmp_path, ext):
    box = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    box.export(tmp_path / f"box.{ext}")
    scene = gi.load_scene(scene_with_mesh(tmp_path, f"box.{ext}"))
    assert scene.triangle_count == 10 + 12  # five wall quads + the box
    r = gi.render(scene, "path", spp=1, size=(16, 16))
    assert np.isfinite(r.radiance).all()


def test_obj_with_mtl_materials(tmp_path):
    (tmp_path / "tri.mtl").write_text("newmtl shiny_red\nKd 0.8 0.1 0.1\n")
    (tmp_path / "tri.obj").write_text(
        "mtllib tri.mtl\nv -0.5 0 0\nv 0.5 0 0\nv 0 1 0\nusemtl shiny_red\nf 1 2 3\n"
    )
    scene = gi.load_scene(scene_with_mesh(tmp_path, "tri.obj", material=False))
    assert any(name.startswith("tri.obj:") for name in scene.material_names)


def test_mesh_without_materials_needs_one(tmp_path):
    trimesh.creation.box().export(tmp_path / "b.stl")
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(scene_with_mesh(tmp_path, "b.stl", material=False))
    assert e.value.field == "objects[5].material"
