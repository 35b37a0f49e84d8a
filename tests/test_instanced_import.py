"""Importers keep shared meshes shared: a glTF file loaded as a scene makes every node that
uses a mesh an instance of one gi mesh per primitive, and the Mitsuba importer makes shapes
that load one file with the same options, equal built-in shapes and the shapes of a
``<shapegroup>`` placed by ``<shape type="instance">`` instances of one mesh (placed by
``matrix`` transforms). Each renders as the same scene flattened into world-space triangles
(the glTF file named as a mesh file; the Mitsuba scene with every shape baked into its own
PLY file), and bad transforms and references are typed errors naming the node, element or
field.

Tolerance of the flattened comparisons: the instanced scene places f32 local vertices by an
f32 matrix, the flattened one stores vertices placed in float64 and rounded once, so the
two differ by float rounding (~1e-7 relative). A rounding changes a pixel only where it
flips a decision: a pixel centre or shadow-map texel on an edge between two triangles
(`direct`), a ray grazing an edge, a Russian-roulette or lobe threshold (`path`). So the
image means agree within 0.5% and at least 97% of pixels within 1e-4 relative (+1e-6
absolute), the bound the core's own instanced-vs-flattened test uses. Measured (40×30):
`direct` 99.2-99.3% of pixels, means within 2.2e-4; `path` (4 spp) 100%, means within
1.2e-7.
"""

import base64
import json
import math
import warnings

import numpy as np
import pytest
import trimesh

import gi
from gi.mitsuba import DISK_SEGMENTS, _cube, _disk

W, H = 40, 30
PATH = {"spp": 4, "seed": 7, "max_depth": 4}


def compare(a, b, method):
    """`a` and `b` renders of one scene differing by float rounding (module doc)."""
    x, y = a.radiance, b.radiance
    close = np.abs(x - y) <= 1e-4 * np.abs(y) + 1e-6
    frac = close.all(axis=-1).mean()
    assert frac >= 0.97, (method, frac)
    assert x.mean() == pytest.approx(y.mean(), rel=5e-3), method
    assert y.mean() > 0.01, "the scene is lit"
    return frac


# -- glTF ------------------------------------------------------------------------------


def _accessor(doc, blob, array, kind, ctype, target=None):
    """Appends `array` to the binary blob with a buffer view and accessor; its index."""
    data = np.ascontiguousarray(array).tobytes()
    view = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
    if target:
        view["target"] = target
    doc["bufferViews"].append(view)
    blob += data + b"\0" * (-len(data) % 4)
    acc = {
        "bufferView": len(doc["bufferViews"]) - 1,
        "componentType": ctype,
        "count": len(array),
        "type": kind,
    }
    if kind == "VEC3":
        acc["min"] = np.asarray(array).min(axis=0).tolist()
        acc["max"] = np.asarray(array).max(axis=0).tolist()
    doc["accessors"].append(acc)
    return len(doc["accessors"]) - 1, blob


def _primitive(doc, blob, verts, faces, material, normals=None):
    pos, blob = _accessor(doc, blob, np.asarray(verts, np.float32), "VEC3", 5126, 34962)
    attrs = {"POSITION": pos}
    if normals is not None:
        attrs["NORMAL"], blob = _accessor(
            doc, blob, np.asarray(normals, np.float32), "VEC3", 5126, 34962
        )
    idx, blob = _accessor(doc, blob, np.asarray(faces, np.uint32).ravel(), "SCALAR", 5125, 34963)
    return {"attributes": attrs, "indices": idx, "material": material}, blob


def shared_mesh_gltf(tmp_path, copies=5):
    """A glTF whose mesh 0 (an icosphere with normals and a box without, two primitives of
    two materials) is used by `copies` nodes (translated, rotated and scaled, mirrored,
    sheared by a `matrix`, under a transformed parent), a floor used once, a perspective
    camera and a point light."""
    ico = trimesh.creation.icosphere(subdivisions=1, radius=0.3)
    box = trimesh.creation.box(extents=[0.2, 0.5, 0.2])
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [],
        "bufferViews": [],
        "accessors": [],
        "materials": [
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1],
                                                      "metallicFactor": 0.0}},
            {"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1],
                                                       "metallicFactor": 0.0,
                                                       "roughnessFactor": 0.7}},
        ],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.9, "aspectRatio": W / H, "znear": 0.01}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 683 * 6, "color": [1, 0.9, 0.8]}]}},
    }  # fmt: skip
    blob = b""
    normals = ico.vertices / np.linalg.norm(ico.vertices, axis=1, keepdims=True)
    p0, blob = _primitive(doc, blob, ico.vertices, ico.faces, 0, normals)
    p1, blob = _primitive(doc, blob, box.vertices + [0.45, 0, 0], box.faces, 1)
    floor_v = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]
    p2, blob = _primitive(doc, blob, floor_v, [[0, 2, 1], [0, 3, 2]], 1)
    doc["meshes"] = [{"primitives": [p0, p1]}, {"primitives": [p2]}]
    shear = np.eye(4)
    shear[0, 1], shear[:3, 3] = 0.4, [1.2, 0.5, -0.6]
    children = [
        {"mesh": 0, "translation": [-1.2, 0.4, 0.0]},
        {"mesh": 0, "translation": [0.0, 0.5, -1.0], "scale": [1.2, 0.8, 1.0],
         "rotation": [0.0, math.sin(0.4), 0.0, math.cos(0.4)]},
        {"mesh": 0, "translation": [0.2, 0.4, 0.8], "scale": [-1.0, 1.0, 1.0]},
        {"mesh": 0, "matrix": shear.T.ravel().tolist()},
    ][: copies - 1]  # fmt: skip
    nodes = [{"name": "group", "translation": [0, 0.1, 0], "rotation": [0, 0.2, 0, 0.98]}]
    nodes[0]["children"] = list(range(1, 1 + len(children)))
    nodes += children
    nodes += [
        {"mesh": 0, "translation": [0.9, 0.35, 1.1]},
        {"name": "floor", "mesh": 1},
        {"camera": 0, "translation": [0, 2.2, 4.0], "rotation": [-0.2588, 0, 0, 0.9659]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.5, 2.5, 1.5]},
    ]
    doc["nodes"] = nodes
    doc["scenes"] = [{"nodes": [0, *range(len(children) + 1, len(nodes))]}]
    doc["buffers"] = [
        {
            "byteLength": len(blob),
            "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode(),
        }
    ]
    path = tmp_path / "shared.gltf"
    path.write_text(json.dumps(doc))
    return path, len(ico.faces) + len(box.faces), 2


@pytest.mark.parametrize("copies", [5])
def test_gltf_nodes_sharing_a_mesh_are_instances_and_render_as_flattened(tmp_path, copies):
    path, mesh_tris, floor_tris = shared_mesh_gltf(tmp_path, copies)
    scene = gi.load_scene(path)
    assert scene.unique_triangle_count == mesh_tris + floor_tris
    assert scene.triangle_count == copies * mesh_tris + floor_tris
    assert scene.light_count == 1
    # The camera's aspect ratio against a height of 512.
    assert (scene.width, scene.height) == (round(512 * W / H), 512)
    # The same file named as a mesh file by a JSON scene: one mesh of world-space
    # triangles (every node's copy), its lights and materials from the file.
    from gi.scene import gltf_scene_description

    desc = gltf_scene_description(path)[0]
    flat_desc = {"camera": desc["camera"], "objects": [{"shape": {"type": "mesh",
                                                                  "file": path.name}}]}  # fmt: skip
    (tmp_path / "flat.json").write_text(json.dumps(flat_desc))
    flat = gi.load_scene(tmp_path / "flat.json")
    assert flat.unique_triangle_count == flat.triangle_count == scene.triangle_count
    assert flat.light_count == 1
    for method, opts in (("direct", {}), ("path", PATH)):
        a = gi.render(scene, method, width=W, height=H, **opts)
        b = gi.render(flat, method, width=W, height=H, **opts)
        compare(a, b, method)


def test_gltf_scene_keeps_the_mesh_file_reading(tmp_path):
    """The instanced reader and the flattened one read the same materials, lights and
    warnings; without a camera the scene is framed from +z."""
    path, _, _ = shared_mesh_gltf(tmp_path)
    doc = json.loads(path.read_text())
    doc["nodes"] = [n for n in doc["nodes"] if "camera" not in n]
    doc["scenes"][0]["nodes"] = [i for i in doc["scenes"][0]["nodes"] if i < len(doc["nodes"])]
    doc["materials"][0]["occlusionTexture"] = {"index": 0}
    path.write_text(json.dumps(doc))
    from gi.gltf import load_gltf, read_gltf

    with pytest.warns(gi.AssetWarning, match="occlusionTexture"):
        scene = gi.load_scene(path)
    # A warning the caller makes an error stays that warning (not a SceneError).
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(gi.AssetWarning):
            gi.load_scene(path)
    assert scene.width == scene.height == 512
    flat, inst = load_gltf(path), read_gltf(path)
    assert flat.materials == inst.materials and flat.lights == inst.lights
    assert flat.warnings == inst.warnings
    placed = sum(len(p.faces) for i in inst.instances for p in inst.meshes[i.mesh])
    assert placed == len(flat.faces)


@pytest.mark.parametrize(
    "node, says",
    [
        ({"mesh": 0, "scale": [1, 0, 1]}, "singular"),
        # Columns (1, 0, 0) and (1, 1e-9, 0): nearly parallel, |det| 1e-9 of their lengths.
        ({"mesh": 0, "matrix": [1, 0, 0, 0, 1, 1e-9, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}, "singular"),
        ({"mesh": 0, "translation": [float("nan"), 0, 0]}, "not finite"),
        ({"mesh": 0, "translation": [2e5, 0, 0]}, "100000"),
    ],
)
def test_bad_gltf_node_transforms_are_errors_naming_the_node(tmp_path, node, says):
    path, _, _ = shared_mesh_gltf(tmp_path)
    doc = json.loads(path.read_text())
    doc["nodes"].append(node)
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    path.write_text(json.dumps(doc))  # NaN is written as Python's json writes it
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.field == f"nodes[{len(doc['nodes']) - 1}]", e.value
    assert says in e.value.reason, e.value.reason


# -- Mitsuba ---------------------------------------------------------------------------


SENSOR = f"""<sensor type="perspective"><float name="fov" value="55"/>
<transform name="to_world"><lookat origin="0, 2.2, 4.5" target="0, 0.4, 0" up="0, 1, 0"/>
</transform><film type="hdrfilm"><integer name="width" value="{W}"/>
<integer name="height" value="{H}"/></film></sensor>
<bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.7, 0.2, 0.1"/></bsdf>
<emitter type="point"><point name="position" value="0.5, 2.5, 1.5"/>
<rgb name="intensity" value="6, 6, 6"/></emitter>"""


def _matrix(t=(0, 0, 0), s=(1, 1, 1), angle=0.0, shear=0.0):
    """Translate · rotate about y (degrees) · shear (x by y) · scale, as a 4×4."""
    m = np.diag([*s, 1.0])
    sh = np.eye(4)
    sh[0, 1] = shear
    c, n = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    r = np.array([[c, 0, n, 0], [0, 1, 0, 0], [-n, 0, c, 0], [0, 0, 0, 1]])
    out = r @ sh @ m
    out[:3, 3] = t
    return out


def _xml_matrix(m):
    return '<transform name="to_world"><matrix value="{}"/></transform>'.format(
        " ".join(repr(float(v)) for v in m.ravel())
    )


def _write_ply(path, verts, faces, normals):
    head = (
        f"ply\nformat ascii 1.0\nelement vertex {len(verts)}\n"
        + "".join(f"property float {a}\n" for a in ("x", "y", "z", "nx", "ny", "nz"))
        + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rows = [" ".join(repr(float(x)) for x in (*v, *n)) for v, n in zip(verts, normals, strict=True)]
    path.write_text(
        head + "\n".join(rows) + "\n" + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces)
    )


RECT = (
    np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64),
    np.array([[0, 1, 2], [0, 2, 3]]),
    np.tile([0.0, 0.0, 1.0], (4, 1)),
)


def mitsuba_instances(tmp_path):
    """A Mitsuba scene of instances: a shapegroup (a cube and a PLY mesh) placed three times
    (one mirrored, one sheared), three rectangles (one an area light), two disks, and the
    PLY file used by three more shapes (one with `face_normals`); and the same scene flattened: each
    placed shape baked (float64) into its own PLY file. Returns both paths and the unique
    and placed triangle counts."""
    ico = trimesh.creation.icosphere(subdivisions=1, radius=0.25)
    normals = ico.vertices / np.linalg.norm(ico.vertices, axis=1, keepdims=True)
    _write_ply(tmp_path / "ball.ply", ico.vertices, ico.faces, normals)
    ball = (np.asarray(ico.vertices), np.asarray(ico.faces), normals)
    cube = _cube()
    group_cube = _matrix(t=(0.4, 0.15, 0), s=(0.15, 0.15, 0.15))
    group_ball = _matrix(t=(0, 0.25, 0))
    instances = [
        _matrix(t=(-1.1, 0, 0.2)),
        _matrix(t=(0.2, 0, -0.8), angle=35, s=(1.2, 0.9, 1.1)),
        _matrix(t=(0.6, 0, 0.9), s=(-1, 1, 1), shear=0.3),
    ]
    rects = [
        ("rectangle", _matrix(s=(3, 3, 1)) @ _rot_x(-90), "white", None),
        ("rectangle", _matrix(t=(0, 1.5, -2), s=(3, 1.5, 1)), "red", None),
        ("rectangle", _matrix(t=(-0.8, 1.8, 0.5), s=(0.3, 0.3, 1)) @ _rot_x(90), "white", "2"),
        # Not emitting: a 128-triangle emitter's sampling table is built from triangle areas
        # that differ by rounding, so light samples (not their expectation) differ.
        ("disk", _matrix(t=(0.9, 1.9, -0.4), s=(0.25, 0.25, 1)) @ _rot_x(90), "white", None),
        ("disk", _matrix(t=(-0.4, 0.8, -1.9), s=(0.5, 0.4, 1)), "red", None),
    ]
    balls = [
        (_matrix(t=(1.4, 0.25, 0.2)), False),
        (_matrix(t=(-0.3, 0.3, 1.3), s=(1.3, 1.3, 1.3)), False),
        (_matrix(t=(-1.5, 0.25, -1.0)), True),
    ]
    inst, flat = [SENSOR], [SENSOR]
    placed: list[tuple] = []  # (mesh arrays, matrix, bsdf, emitter radiance, flat shading)
    inst.append(
        '<shapegroup id="thing">'
        f'<shape type="cube">{_xml_matrix(group_cube)}<ref id="red"/></shape>'
        f'<shape type="ply"><string name="filename" value="ball.ply"/>{_xml_matrix(group_ball)}'
        '<ref id="white"/></shape></shapegroup>'
    )
    for m in instances:
        inst.append(f'<shape type="instance"><ref id="thing"/>{_xml_matrix(m)}</shape>')
        placed += [(cube, m @ group_cube, "red", None, False)]
        placed += [(ball, m @ group_ball, "white", None, False)]
    for kind, m, bsdf, radiance in rects:
        emitter = (
            f'<emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter>'
            if radiance
            else ""
        )
        inst.append(f'<shape type="{kind}">{_xml_matrix(m)}<ref id="{bsdf}"/>{emitter}</shape>')
        placed.append((RECT if kind == "rectangle" else _disk(), m, bsdf, radiance, False))
    for m, faceted in balls:
        fn = '<boolean name="face_normals" value="true"/>' if faceted else ""
        inst.append(
            f'<shape type="ply"><string name="filename" value="ball.ply"/>{fn}'
            f'{_xml_matrix(m)}<ref id="white"/></shape>'
        )
        placed.append((ball, m, "white", None, faceted))
    for i, ((v, f, n), m, bsdf, radiance, faceted) in enumerate(placed):
        lin = m[:3, :3]
        if np.linalg.det(lin) < 0:
            f = f[:, [0, 2, 1]]
        wn = n @ np.linalg.inv(lin)
        wn /= np.linalg.norm(wn, axis=1, keepdims=True)
        _write_ply(tmp_path / f"flat{i}.ply", v @ lin.T + m[:3, 3], f, wn)
        fn = '<boolean name="face_normals" value="true"/>' if faceted else ""
        emitter = (
            f'<emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter>'
            if radiance
            else ""
        )
        flat.append(
            f'<shape type="ply"><string name="filename" value="flat{i}.ply"/>{fn}'
            f'<ref id="{bsdf}"/>{emitter}</shape>'
        )
    for name, body in (("inst.xml", inst), ("flat.xml", flat)):
        (tmp_path / name).write_text('<scene version="3.0.0">\n' + "\n".join(body) + "\n</scene>\n")
    # Unique: cube, ball (smooth, as stored), ball (face_normals), rectangle, disk.
    unique = 12 + 2 * len(ico.faces) + 2 + DISK_SEGMENTS
    return tmp_path / "inst.xml", tmp_path / "flat.xml", unique, sum(len(p[0][1]) for p in placed)


def _rot_x(angle):
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def test_mitsuba_instances_share_meshes_and_render_as_flattened(tmp_path):
    inst_path, flat_path, unique, placed = mitsuba_instances(tmp_path)
    inst, flat = gi.load_scene(inst_path), gi.load_scene(flat_path)
    assert inst.unique_triangle_count == unique
    assert inst.triangle_count == flat.triangle_count == flat.unique_triangle_count == placed
    for method, opts in (("direct", {}), ("path", PATH)):
        compare(gi.render(inst, method, **opts), gi.render(flat, method, **opts), method)


def _write(tmp_path, body):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{SENSOR}\n{body}\n</scene>\n')
    return path


GROUP = '<shapegroup id="g"><shape type="cube"/></shapegroup>'


@pytest.mark.parametrize(
    "body, element, says",
    [
        (f'{GROUP}\n<shape type="instance"><ref id="nowhere"/></shape>', "<ref>", "nowhere"),
        (f'{GROUP}\n<shape type="instance"/>', '<shape type="instance">', "one <shapegroup>"),
        (
            f'{GROUP}\n<shape type="instance"><ref id="white"/></shape>',
            "<ref>",
            "not a <shapegroup>",
        ),
        (
            '<shapegroup id="g">\n<shape type="instance"><ref id="g"/></shape></shapegroup>',
            '<shape type="instance">',
            "recursive",
        ),
        (
            '<shapegroup id="h"><shape type="cube"/></shapegroup>\n<shapegroup id="g">\n'
            '<shape type="instance"><ref id="h"/></shape></shapegroup>',
            '<shape type="instance">',
            "nested instancing",
        ),
        (
            '<shapegroup id="g">\n<shapegroup id="h"/></shapegroup>',
            "<shapegroup>",
            "nested",
        ),
        (
            f'{GROUP}\n<shape type="instance"><ref id="g"/><transform name="to_world">'
            '<scale value="1, 0, 1"/></transform></shape>',
            '<shape type="cube">',
            "scales an axis",
        ),
        (
            '<shape type="rectangle"><transform name="to_world">'
            '<matrix value="1 1 0 0 0 0.000001 0 0 0 0 1 0 0 0 0 1"/></transform></shape>',
            '<transform name="to_world">',
            "singular",
        ),
    ],
)
def test_bad_mitsuba_instances_are_errors_naming_the_element(tmp_path, body, element, says):
    path = _write(tmp_path, body)
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    line = (
        path.read_text()
        .splitlines()
        .index(next(x for x in path.read_text().splitlines() if element.rstrip(">") in x))
    )
    assert e.value.field.startswith(element), e.value.field
    assert f"(line {line + 1})" in e.value.field or "(line" in e.value.field
    assert says in e.value.reason, e.value.reason


def test_an_unused_shapegroup_places_nothing(tmp_path):
    body = GROUP + '\n<shape type="rectangle"><ref id="white"/></shape>'
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = gi.load_scene(_write(tmp_path, body))
    assert scene.triangle_count == 2


# -- scene format ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "matrix, field, says",
    [
        # Two equal columns; two nearly parallel ones (|det| 1e-9 of their lengths' product);
        # an axis scaled by 1e-9.
        ([[1, 1, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0]], "objects[0].transform.matrix", "singular"),
        ([[1, 1, 0, 0], [0, 1e-9, 0, 0], [0, 0, 1, 0]], "objects[0].transform.matrix", "singular"),
        ([[1, 0, 0, 0], [0, 1e-9, 0, 0], [0, 0, 1, 0]], "objects[0].transform.matrix", "[1e-6"),
        ([[1e39, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "objects[0].transform.matrix", "finite"),
        ([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 1]], "objects[0].transform.matrix[3]",
         "affine"),
    ],
)  # fmt: skip
def test_bad_matrix_transforms_are_scene_errors_naming_the_field(
    write_scene, cornell_desc, matrix, field, says
):
    cornell_desc["objects"][0]["transform"] = {"matrix": matrix}
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(write_scene(cornell_desc))
    assert e.value.field == field and says in e.value.reason, (e.value.field, e.value.reason)


def test_renderer_update_takes_a_matrix(cornell_desc, write_scene):
    cornell_desc["objects"][-1]["name"] = "box"
    scene = gi.load_scene(write_scene(cornell_desc))
    r = gi.Renderer(scene, "path", width=16, height=16, spp=1)
    rows = [[0, 0, 1, 0.1], [0, 1, 0, 0.0], [-1, 0, 0, 0.2]]
    r.update(objects={"box": {"matrix": rows}})
    assert np.allclose(r.describe("object", "box")["matrix"], [*rows, [0, 0, 0, 1]])
    with pytest.raises(gi.SceneError, match=r"objects\[\d+\]\.transform\.matrix"):
        r.update(objects={"box": {"matrix": [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}})


def test_mesh_file_lights_are_placed_by_a_matrix_transform(tmp_path):
    """A glTF mesh file's light follows its object's ``matrix`` as it follows a
    translate/rotate/scale: the point light 2 m above the file's plane, the object scaled
    by 2 (rows of the matrix) and raised by 1 m, lands at y = 5."""
    from test_lights_import import looking_down, plane_gltf

    node = {"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}
    mesh = plane_gltf(tmp_path, [{"type": "point", "intensity": 683}], [node])
    rows = [[2, 0, 0, 0], [0, 2, 0, 1], [0, 0, 2, 0]]
    scene = gi.load_scene(looking_down(tmp_path, mesh, transform={"matrix": rows}))
    r = gi.Renderer(scene, "path", spp=1, max_depth=1)
    assert r.describe("light", 0)["position"] == pytest.approx([0, 5, 0])


def test_gi_render_reads_a_gltf_scene(tmp_path):
    import subprocess
    import sys

    path, _, _ = shared_mesh_gltf(tmp_path)
    out = tmp_path / "g.png"
    p = subprocess.run(
        [sys.executable, "-m", "gi.cli", "render", str(path), "-o", str(out), "--spp", "1",
         "--size", "16x12", "-q"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert gi.read_image(out).shape == (12, 16, 3)


def test_gltf_gpu_instancing_places_the_mesh_as_child_nodes_would(tmp_path):
    """``EXT_mesh_gpu_instancing`` (required here): a node's TRANSLATION/ROTATION/SCALE
    accessors place its mesh three times, as three child nodes with the same (float32)
    values would: the same world matrices (bitwise), one mesh, and bitwise equal images."""
    path, mesh_tris, floor_tris = shared_mesh_gltf(tmp_path, copies=1)
    doc = json.loads(path.read_text())
    t = np.array([[1.5, 0.3, 0.5], [-0.4, 0.3, 1.2], [0.2, 1.2, -1.5]], np.float32)
    half = np.array([0.3, 0.9, -1.2], np.float32) / 2
    q = np.zeros((3, 4), np.float32)
    q[:, 1], q[:, 3] = np.sin(half), np.cos(half)
    s = np.array([[1, 1, 1], [0.5, 0.7, 0.5], [-1, 1, 1]], np.float32)
    blob = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
    attrs = {}
    for name, arr, kind in (
        ("TRANSLATION", t, "VEC3"),
        ("ROTATION", q, "VEC4"),
        ("SCALE", s, "VEC3"),
    ):
        attrs[name], blob = _accessor(doc, blob, arr, kind, 5126)
    doc["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(blob).decode()}  # fmt: skip
    instanced = json.loads(json.dumps(doc))
    node = {"mesh": 0, "translation": [0.1, 0, 0]}
    instanced["nodes"].append(
        {**node, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": attrs}}}
    )
    instanced["extensionsUsed"] += ["EXT_mesh_gpu_instancing"]
    instanced["extensionsRequired"] = ["EXT_mesh_gpu_instancing"]
    instanced["scenes"][0]["nodes"].append(len(instanced["nodes"]) - 1)
    first = len(doc["nodes"]) + 1
    children = [
        {"mesh": 0, "translation": a.tolist(), "rotation": b.tolist(), "scale": c.tolist()}
        for a, b, c in zip(t, q, s, strict=True)
    ]
    doc["nodes"] += [{"translation": [0.1, 0, 0], "children": [first, first + 1, first + 2]}]
    doc["nodes"] += children
    doc["scenes"][0]["nodes"].append(first - 1)
    from gi.scene import gltf_scene_description

    scenes = []
    for name, d in (("inst.gltf", instanced), ("nodes.gltf", doc)):
        (tmp_path / name).write_text(json.dumps(d))
        desc = gltf_scene_description(tmp_path / name)[0]
        scenes.append((gi.load_scene(tmp_path / name), desc))
    (a, da), (b, db) = scenes
    ma = [o["transform"]["matrix"] for o in da["objects"]]
    mb = [o["transform"]["matrix"] for o in db["objects"]]
    assert ma == mb
    names = [o["name"] for o in da["objects"]]
    assert f"nodes[{first - 1}].instances[2].primitives[1]" in names, names
    assert a.unique_triangle_count == b.unique_triangle_count == mesh_tris + floor_tris
    assert a.triangle_count == b.triangle_count == 4 * mesh_tris + floor_tris
    ra, rb = gi.render(a, "direct", width=W, height=H), gi.render(b, "direct", width=W, height=H)
    assert np.array_equal(ra.radiance, rb.radiance)


@pytest.mark.parametrize(
    "counts, scale, field, says",
    [
        ((3, 2), 1.0, ".extensions.EXT_mesh_gpu_instancing.attributes", "one count"),
        ((3, 3), 0.0, "", "singular"),
    ],
)
def test_bad_gltf_gpu_instancing_is_an_error_naming_the_node(tmp_path, counts, scale, field, says):
    path, _, _ = shared_mesh_gltf(tmp_path, copies=1)
    doc = json.loads(path.read_text())
    blob = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
    t, blob = _accessor(doc, blob, np.zeros((counts[0], 3), np.float32), "VEC3", 5126)
    s, blob = _accessor(doc, blob, np.full((counts[1], 3), scale, np.float32), "VEC3", 5126)
    doc["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(blob).decode()}  # fmt: skip
    ext = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": t, "SCALE": s}}}
    doc["nodes"].append({"mesh": 0, "extensions": ext})
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    path.write_text(json.dumps(doc))
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.field == f"nodes[{len(doc['nodes']) - 1}]{field}", e.value
    assert says in e.value.reason, e.value.reason
