"""Users' mesh files render right: per-face materials, flat shading where a file has no
normals, mirrored nodes, glTF material defaults, and warnings for what gi does not render.
Every file is made here with trimesh or numpy, as exporters write them."""

import json
import struct
import subprocess
import sys
import warnings

import numpy as np
import pytest
import trimesh
from trimesh.visual.material import PBRMaterial, SimpleMaterial

import gi
from gi.gltf import load_gltf

BLUE, RED = [0.1, 0.2, 0.9], [0.9, 0.15, 0.1]


def viewing_scene(tmp_path, filename, **obj_fields):
    """A camera at z = 3 looking at the origin, one point light, the mesh file as object."""
    desc = {
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 45},
        "lights": [{"type": "point", "position": [0, 2, 3], "intensity": [5, 5, 5]}],
        "materials": {"grey": {"diffuse": [0.5, 0.5, 0.5]}},
        "objects": [{"shape": {"type": "mesh", "file": filename}, **obj_fields}],
    }
    path = tmp_path / f"{filename}.json"
    path.write_text(json.dumps(desc))
    return path


def left_right_albedo(scene):
    """Mean albedo of the left and right thirds of the image where a surface is seen."""
    r = gi.render(scene, "path", spp=1, size=(48, 32), seed=1)
    hit = r.depth > 0
    out = []
    for cols in (slice(0, 16), slice(32, 48)):
        mask = hit[:, cols]
        assert mask.sum() > 20, "the object should fill part of this third"
        out.append(r.albedo[:, cols][mask].mean(axis=0))
    return out


def two_objects(material_cls, **kw):
    """A box on the left (material `zblue`), a sphere on the right (`red`): first seen and
    alphabetical order differ, which is how materials got swapped."""
    box = trimesh.creation.box(extents=(0.8, 0.8, 0.8))
    box.apply_translation([-0.7, 0, 0])
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.45)
    ball.apply_translation([0.7, 0, 0])
    scene = trimesh.Scene()
    for mesh, name, rgb in ((box, "zblue", BLUE), (ball, "red", RED)):
        mesh.visual = trimesh.visual.TextureVisuals(material=material_cls(name, rgb, **kw))
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    return scene


def simple(name, rgb):
    return SimpleMaterial(name=name, diffuse=[*(np.array(rgb) * 255).round().astype(int), 255])


def pbr(name, rgb):
    return PBRMaterial(name=name, baseColorFactor=[*rgb, 1.0], metallicFactor=0.0)


def assert_blue_left_red_right(scene):
    left, right = left_right_albedo(scene)
    # The diffuse colours differ by 0.8 between the blue and red channels; exporters add a
    # grey specular (trimesh writes Ks 0.4), which lifts all channels alike. A swap would
    # make each object the other's colour.
    assert left[2] - left[0] > 0.4, f"left object should be blue, albedo {left}"
    assert right[0] - right[2] > 0.4, f"right object should be red, albedo {right}"


def test_obj_with_two_materials_keeps_each_on_its_faces(tmp_path):
    two_objects(simple).export(tmp_path / "two.obj")
    text = (tmp_path / "two.obj").read_text()
    order = [line.split()[1] for line in text.splitlines() if line.startswith("usemtl")]
    assert order == ["zblue", "red"], "the file must list materials out of alphabetical order"
    assert "Kd" in (tmp_path / "material.mtl").read_text()
    scene = gi.load_scene(viewing_scene(tmp_path, "two.obj"))
    assert sorted(scene.material_names) == ["grey", "two.obj:red", "two.obj:zblue"]
    assert_blue_left_red_right(scene)


def test_gltf_with_two_materials_keeps_each_on_its_faces(tmp_path):
    two_objects(pbr).export(tmp_path / "two.glb")
    scene = gi.load_scene(viewing_scene(tmp_path, "two.glb"))
    assert_blue_left_red_right(scene)


def test_object_material_overrides_the_files(tmp_path):
    two_objects(pbr).export(tmp_path / "two.glb")
    left, right = left_right_albedo(
        gi.load_scene(viewing_scene(tmp_path, "two.glb", material="grey"))
    )
    assert np.allclose(left, 0.5, atol=0.02) and np.allclose(right, 0.5, atol=0.02)


def distinct_normals(scene):
    """Distinct shading normals (rounded to 1e-3) over the pixels that see the object."""
    r = gi.render(scene, "path", spp=1, size=(48, 32), seed=1)
    n = r.normal[r.depth > 0]
    return len(np.unique(np.round(n, 3), axis=0))


def rotated_box():
    box = trimesh.creation.box(extents=(1, 1, 1))
    box.apply_transform(trimesh.transformations.euler_matrix(0.5, 0.6, 0.0))
    return box


@pytest.mark.parametrize("ext", ["obj", "ply", "glb"])
def test_box_without_normals_is_shaded_flat(tmp_path, ext):
    box = rotated_box()
    kw = {"include_normals": False} if ext == "obj" else {}
    box.export(tmp_path / f"box.{ext}", **kw)
    if ext == "obj":
        assert "vn " not in (tmp_path / "box.obj").read_text()
    flat = gi.load_scene(viewing_scene(tmp_path, f"box.{ext}", material="grey"))
    # Three faces are in view: three normals (the issue measured 1316 with smooth ones).
    assert distinct_normals(flat) == 3
    smooth = gi.load_scene(viewing_scene(tmp_path, f"box.{ext}", material="grey", smooth=True))
    assert distinct_normals(smooth) > 100
    creased = gi.load_scene(viewing_scene(tmp_path, f"box.{ext}", material="grey", smooth=30))
    assert distinct_normals(creased) == 3  # 90° edges are sharper than 30°


def test_smooth_option_on_a_sphere_and_files_with_normals(tmp_path):
    ball = trimesh.creation.icosphere(subdivisions=2)
    ball.export(tmp_path / "ball.ply")  # no normals
    many = distinct_normals(gi.load_scene(viewing_scene(tmp_path, "ball.ply", material="grey")))
    assert many < 200  # flat: one per visible face (a few hundred triangles in view)
    auto = gi.load_scene(viewing_scene(tmp_path, "ball.ply", material="grey", smooth=30))
    # Neighbouring faces of a subdivision-2 icosphere meet at about 12°, below 30°: smooth.
    assert distinct_normals(auto) > 3 * many
    # The same sphere with its exact normals stored (a unit sphere's are its positions).
    with_normals = trimesh.Trimesh(ball.vertices, ball.faces, vertex_normals=ball.vertices)
    with_normals.export(tmp_path / "ball_n.ply")
    assert b"nx" in (tmp_path / "ball_n.ply").read_bytes()[:400]
    kept = gi.load_scene(viewing_scene(tmp_path, "ball_n.ply", material="grey"))
    assert distinct_normals(kept) > 3 * many
    flat = gi.load_scene(viewing_scene(tmp_path, "ball_n.ply", material="grey", smooth=False))
    assert distinct_normals(flat) == many


@pytest.mark.parametrize("bad", ["yes", 200, -1, [1]])
def test_smooth_option_is_validated(tmp_path, bad):
    rotated_box().export(tmp_path / "box.ply")
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(viewing_scene(tmp_path, "box.ply", material="grey", smooth=bad))
    assert e.value.field.startswith("objects[0]")


def signed_volume(scene):
    v, f = scene.mesh_arrays()
    v = v.astype(np.float64)
    return np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6


def test_mirrored_gltf_node_keeps_the_box_outward_facing(tmp_path):
    box = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    scene = trimesh.Scene()
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    mirror[:3, 3] = [0.2, 0, 0]
    scene.add_geometry(box, node_name="mirrored", transform=mirror)
    scene.export(tmp_path / "m.glb")
    doc = glb_json(tmp_path / "m.glb")
    assert np.linalg.det(np.array(doc["nodes"][0]["matrix"]).reshape(4, 4)) < 0
    loaded = gi.load_scene(viewing_scene(tmp_path, "m.glb", material="grey"))
    # Counter-clockwise winding seen from outside gives a positive volume; inside-out
    # triangles (glass refracting the wrong way) give -0.125.
    assert signed_volume(loaded) == pytest.approx(0.125, rel=1e-5)
    # The same for a mirroring object transform in the scene file (the core's flip).
    mirrored_obj = viewing_scene(
        tmp_path, "m.glb", material="grey", transform={"scale": [1, 1, -2]}
    )
    assert signed_volume(gi.load_scene(mirrored_obj)) == pytest.approx(0.25, rel=1e-5)


def glb_json(path):
    data = path.read_bytes()
    (length,) = struct.unpack_from("<I", data, 12)
    return json.loads(data[20 : 20 + length])


def write_gltf(tmp_path, name, materials, extra_attrs=None):
    """A glTF (JSON + embedded buffer) with one box primitive per material."""
    import base64

    box = trimesh.creation.box()
    v = np.asarray(box.vertices, np.float32)
    f = np.asarray(box.faces, np.uint32)
    blob = v.tobytes() + f.tobytes()
    attrs = {"POSITION": 0}
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
         "min": v.min(0).tolist(), "max": v.max(0).tolist()},
        {"bufferView": 1, "componentType": 5125, "count": f.size, "type": "SCALAR"},
    ]  # fmt: skip
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": v.nbytes},
        {"buffer": 0, "byteOffset": v.nbytes, "byteLength": f.nbytes},
    ]
    if extra_attrs:
        colours = np.ones((len(v), 4), np.float32)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": colours.nbytes})
        accessors.append({"bufferView": 2, "componentType": 5126, "count": len(v), "type": "VEC4"})
        attrs["COLOR_0"] = 2
        blob += colours.tobytes()
        tangents = np.tile(np.float32([1, 0, 0, 1]), (len(v), 1))
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": tangents.nbytes})
        accessors.append({"bufferView": 3, "componentType": 5126, "count": len(v), "type": "VEC4"})
        attrs["TANGENT"] = 3
        blob += tangents.tobytes()
    uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(materials)))}],
        "nodes": [{"mesh": i, "translation": [2.0 * i, 0, 0]} for i in range(len(materials))],
        "meshes": [
            {"primitives": [{"attributes": attrs, "indices": 1, "material": i}]}
            for i in range(len(materials))
        ],
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": uri}],
    }
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


def test_gltf_material_defaults_and_exact_factors(tmp_path):
    path = write_gltf(
        tmp_path,
        "mats.gltf",
        [
            {"name": "nometal", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.1, 1]}},
            {"name": "dark", "pbrMetallicRoughness": {"baseColorFactor": [0.002, 0.003, 0.004, 1],
             "metallicFactor": 0.0}},
            {"name": "empty"},
        ],
    )  # fmt: skip
    mats = dict(load_gltf(path).materials)
    # No metallicFactor: glTF's default 1, a metal: no diffuse, specular = base colour.
    nometal = mats["mats.gltf:nometal"]
    assert nometal["diffuse"] == [0, 0, 0]
    assert nometal["specular"] == pytest.approx([0.9, 0.5, 0.1])
    assert nometal["roughness"] == 1.0
    # A dark factor stays dark (8-bit storage made it 1/255, then read as 0-1: white).
    assert mats["mats.gltf:dark"]["diffuse"] == pytest.approx([0.002, 0.003, 0.004], abs=1e-7)
    # No pbrMetallicRoughness at all: white metal, roughness 1.
    assert mats["mats.gltf:empty"]["specular"] == pytest.approx([1, 1, 1])
    scene = gi.load_scene(viewing_scene(tmp_path, "mats.gltf"))
    assert "mats.gltf:dark" in scene.material_names


def test_unrendered_features_warn_once_naming_file_and_field(tmp_path):
    path = write_gltf(
        tmp_path,
        "lamp.gltf",
        [
            # BLEND is rendered as a mask; the texture names no image. Emission is read
            # (tests/test_lights_import.py), occlusion maps are not.
            {"name": "glow", "emissiveFactor": [1, 0.5, 0], "alphaMode": "BLEND",
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
             "occlusionTexture": {"index": 0}},
            {"name": "glow2", "emissiveFactor": [1, 0.5, 0], "occlusionTexture": {"index": 0}},
        ],
        extra_attrs=True,
    )  # fmt: skip
    with pytest.warns(gi.AssetWarning) as record:
        gi.load_scene(viewing_scene(tmp_path, "lamp.gltf"))
    fields = sorted(w.message.field for w in record)
    # Occlusion maps are explained once per file; stored tangents are read (no warning).
    assert fields == sorted(
        [
            "materials[*].occlusionTexture",
            "materials[0].alphaMode",
            "materials[0].pbrMetallicRoughness.baseColorTexture",
            "meshes[0].primitives[0].attributes.COLOR_0",
            "meshes[1].primitives[0].attributes.COLOR_0",
        ]
    )
    assert all(w.message.file == str(path) for w in record)
    assert dict(load_gltf(path).materials)["lamp.gltf:glow2"]["emission"] == [1, 0.5, 0]


def test_obj_emission_is_read_textures_and_vertex_colours_warn(tmp_path):
    (tmp_path / "lamp.mtl").write_text(
        "newmtl shade\nKd 0.8 0.8 0.8\nKe 4 4 4\nmap_Kd wood.png\n"
        "newmtl plain\nKd 0.2 0.2 0.2\nKs 0.5 0.5 0.5\nNs 100\n"
    )
    box = trimesh.creation.box()
    lines = ["mtllib lamp.mtl"]
    lines += [f"v {x} {y} {z} 1 0 0" for x, y, z in box.vertices]
    lines += ["usemtl shade"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces[:6]]
    lines += ["usemtl plain"] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces[6:]]
    (tmp_path / "lamp.obj").write_text("\n".join(lines) + "\n")
    with pytest.warns(gi.AssetWarning) as record:
        scene = gi.load_scene(viewing_scene(tmp_path, "lamp.obj"))
    fields = sorted(w.message.field for w in record)
    assert fields == [
        "lamp.mtl: newmtl shade: map_Kd",
        "v (vertex colours)",
    ]
    assert sorted(scene.material_names) == ["grey", "lamp.obj:plain", "lamp.obj:shade"]
    shade = gi.Renderer(scene, "path", size=(4, 4)).describe("material", "lamp.obj:shade")
    assert shade["emission"] == [4, 4, 4]


def test_ply_vertex_colours_warn(tmp_path):
    box = trimesh.creation.box()
    box.visual.vertex_colors = np.tile([255, 0, 0, 255], (len(box.vertices), 1))
    box.export(tmp_path / "c.ply")
    with pytest.warns(gi.AssetWarning, match="vertex colours are not supported"):
        gi.load_scene(viewing_scene(tmp_path, "c.ply", material="grey"))


def test_plain_files_load_without_warnings(tmp_path):
    two_objects(pbr).export(tmp_path / "two.glb")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gi.load_scene(viewing_scene(tmp_path, "two.glb"))


def test_large_mesh_without_normals_loads_quietly(tmp_path):
    # A user's scan: a PLY without normals (20k triangles here; the 80k benchmark is in
    # docs/scene-format.md). Loading used to compute trimesh vertex normals, which without
    # scipy took tens of seconds and printed a ModuleNotFoundError traceback. Checked
    # directly: trimesh's vertex normals raise if asked for (whether scipy is installed, or
    # imported by something else, says nothing: the GPU machine's Python has it).
    ball = trimesh.creation.icosphere(subdivisions=5)
    ball.export(tmp_path / "scan.ply")
    scene_file = viewing_scene(tmp_path, "scan.ply", material="grey")
    code = (
        "import sys, trimesh\n"
        "def refuse(mesh):\n"
        "    raise AssertionError('trimesh vertex normals computed')\n"
        "trimesh.Trimesh.vertex_normals = property(refuse)\n"
        "import gi\n"
        "s = gi.load_scene(sys.argv[1])\n"
        "print(s.triangle_count, 'normals-not-computed')\n"
    )
    p = subprocess.run(
        [sys.executable, "-c", code, str(scene_file)], capture_output=True, text=True, timeout=120
    )
    assert p.returncode == 0, p.stderr
    assert p.stderr == ""
    count, verdict = p.stdout.split()
    assert int(count) == len(ball.faces) and verdict == "normals-not-computed"


def test_gltf_requiring_an_unread_extension_is_a_scene_error(tmp_path):
    # (Draco is read: tests/test_gltf.py.)
    path = write_gltf(tmp_path, "volume.gltf", [{"name": "m"}])
    doc = json.loads(path.read_text())
    doc["extensionsRequired"] = ["KHR_materials_volume"]
    path.write_text(json.dumps(doc))
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(viewing_scene(tmp_path, "volume.gltf"))
    assert e.value.field == "objects[0].shape.file"
    assert "extensionsRequired: unsupported extension KHR_materials_volume" in str(e.value)


def test_cli_prints_asset_warnings(tmp_path):
    path = write_gltf(tmp_path, "lamp.gltf", [{"name": "ao", "occlusionTexture": {"index": 0}}])
    scene = viewing_scene(tmp_path, "lamp.gltf")
    out = tmp_path / "o.png"
    p = subprocess.run(
        [sys.executable, "-m", "gi.cli", "render", str(scene), "-o", str(out), "--spp", "1",
         "--size", "8x8", "--method", "path", "-q"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    assert p.stderr == (
        f"gi: warning: {path}: materials[*].occlusionTexture: ignored: gi computes how much"
        " light reaches each point by tracing it, so a baked ambient-occlusion map would"
        " darken what the light transport already shadows (first: materials[0])\n"
    )


def test_gltf_lights_and_animations_warn(tmp_path):
    path = write_gltf(tmp_path, "anim.gltf", [{"name": "m", "pbrMetallicRoughness": {}}])
    doc = json.loads(path.read_text())
    doc["nodes"][0]["extensions"] = {"KHR_lights_punctual": {"light": 0}}
    doc["animations"] = [{"channels": [], "samplers": []}]
    path.write_text(json.dumps(doc))
    with pytest.warns(gi.AssetWarning) as rec:
        gi.load_scene(viewing_scene(tmp_path, "anim.gltf"))
    assert sorted(w.message.field for w in rec) == [
        "animations",
        "nodes[0].extensions.KHR_lights_punctual",
    ]
