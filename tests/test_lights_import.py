"""The lights users' files bring: glTF `KHR_lights_punctual` lights (with their photometric
units converted) and emissive materials, OBJ/MTL `Ke`, Mitsuba area and directional
emitters; and the scene format's emission and directional light through `Renderer.update`,
`describe` and animation tracks. Files are made here (trimesh, numpy) as exporters write
them; light units are checked against analytic radiance with method `path`."""

import json
import math
import warnings

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)
import pytest
import trimesh
from trimesh.visual.material import PBRMaterial

import gi
from gi.gltf import LUMENS_PER_WATT

ALBEDO = 0.5


def export_gltf(scene, tmp_path, name):
    """trimesh's glTF export of `scene`, its buffers written beside `name` (their names
    prefixed with it), the JSON returned for the test to add to."""
    files = scene.export(file_type="gltf")
    doc = json.loads(files.pop("model.gltf"))
    for buffer in doc["buffers"]:
        (tmp_path / f"{name}.{buffer['uri']}").write_bytes(files[buffer["uri"]])
        buffer["uri"] = f"{name}.{buffer['uri']}"
    return doc


def plane_gltf(tmp_path, lights, nodes, material=None, name="lit.gltf"):
    """A 20 m square plane (y = 0, facing +y) exported by trimesh, then given
    `KHR_lights_punctual` lights on extra nodes, as Blender writes them."""
    plane = trimesh.Trimesh(
        vertices=[[-10, 0, -10], [10, 0, -10], [10, 0, 10], [-10, 0, 10]],
        faces=[[0, 2, 1], [0, 3, 2]],
        process=False,
    )
    mat = material or PBRMaterial(
        name="floor", baseColorFactor=[ALBEDO, ALBEDO, ALBEDO, 1.0], metallicFactor=0.0
    )
    plane.visual = trimesh.visual.TextureVisuals(material=mat)
    doc = export_gltf(trimesh.Scene(plane), tmp_path, name)
    doc.setdefault("extensions", {})["KHR_lights_punctual"] = {"lights": lights}
    doc.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
    first = len(doc["nodes"])
    doc["nodes"] += nodes
    doc["scenes"][doc.get("scene", 0)]["nodes"] += list(range(first, first + len(nodes)))
    (tmp_path / name).write_text(json.dumps(doc))
    return name


def looking_down(tmp_path, mesh, material="lambert", transform=None, size=5):
    """A camera 5 m above the origin looking straight down with a narrow view (the pixels
    see the plane within a few centimetres of the origin)."""
    obj = {"shape": {"type": "mesh", "file": mesh}}
    if material:
        obj["material"] = material
    if transform:
        obj["transform"] = transform
    desc = {
        "camera": {"position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov": 1,
                   "width": size, "height": size},
        "materials": {"lambert": {"diffuse": [ALBEDO] * 3}},
        "objects": [obj],
    }  # fmt: skip
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(desc))
    return path


# A node rotation that turns the light's -z axis to -y (straight down): -90° about x.
DOWN = [-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]


@pytest.mark.parametrize(
    "light, node, expected",
    [
        # Point light of 500 cd, 2 m above the plane: E = I/d², L = ρ/π · E.
        ({"type": "point", "intensity": 500}, {"translation": [0, 2, 0]}, 500 / 4),
        # Spot of 300 cd on its axis (inside the inner cone), 1.5 m above the plane.
        (
            {
                "type": "spot",
                "intensity": 300,
                "color": [1, 0.5, 0.25],
                "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.5},
            },
            {"translation": [0, 1.5, 0], "rotation": DOWN},
            np.array([1, 0.5, 0.25]) * 300 / 1.5**2,
        ),
        # Directional light of 1000 lux, turned 60° from the vertical: E = 1000 · cos 60°.
        (
            {"type": "directional", "intensity": 1000},
            {"rotation": [-math.sin(math.radians(15)), 0, 0, math.cos(math.radians(15))]},
            1000 * math.cos(math.radians(60)),
        ),
    ],
    ids=["point", "spot", "directional"],
)
def test_gltf_punctual_lights_in_photometric_units(tmp_path, light, node, expected):
    node = {**node, "extensions": {"KHR_lights_punctual": {"light": 0}}}
    mesh = plane_gltf(tmp_path, [light], [node])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = gi.load_scene(looking_down(tmp_path, mesh))
    assert scene.light_count == 1
    r = gi.render(scene, "path", spp=4, max_depth=1, seed=1)
    # Lambertian plane: L = ρ/π · E, E in lux / 683 (W/m²) for photometric E in lux.
    want = np.broadcast_to(ALBEDO / math.pi * np.asarray(expected) / LUMENS_PER_WATT, (3,))
    got = r.radiance[2, 2]
    assert np.allclose(got, want, rtol=0.01), (got, want)


def test_gltf_lights_move_with_their_object(tmp_path):
    """A light in a mesh file is placed by its object's transform: a point light 2 m above
    the file's plane; the object scaled by 2 and raised by 1 m puts the plane at y = 1 and
    the light at y = 5, 4 m above it."""
    node = {"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}
    mesh = plane_gltf(tmp_path, [{"type": "point", "intensity": 683}], [node])
    path = looking_down(tmp_path, mesh, transform={"scale": 2, "translate": [0, 1, 0]})
    desc = json.loads(path.read_text())
    desc["camera"].update(position=[0, 4.5, 0], look_at=[0, 1, 0])
    path.write_text(json.dumps(desc))
    scene = gi.load_scene(path)
    r = gi.Renderer(scene, "path", spp=4, max_depth=1, seed=1)
    assert r.describe("light", 0)["position"] == pytest.approx([0, 5, 0])
    got = r.render().radiance[2, 2]
    assert np.allclose(got, ALBEDO / math.pi * 1 / 4**2, rtol=0.01), got


def test_gltf_light_ranges_and_unknown_types_warn(tmp_path):
    lights = [
        {"type": "point", "intensity": 10, "range": 5},
        {"type": "area", "intensity": 10},
        {"type": "spot", "spot": {"outerConeAngle": math.pi / 2}},
    ]
    nodes = [{"extensions": {"KHR_lights_punctual": {"light": i}}} for i in range(3)]
    nodes.append({"extensions": {"KHR_lights_punctual": {"light": 7}}})
    mesh = plane_gltf(tmp_path, lights, nodes)
    with pytest.warns(gi.AssetWarning) as rec:
        scene = gi.load_scene(looking_down(tmp_path, mesh))
    assert sorted(w.message.field for w in rec) == [
        "extensions.KHR_lights_punctual.lights[0].range",
        "extensions.KHR_lights_punctual.lights[1].type",
        "extensions.KHR_lights_punctual.lights[2].spot.outerConeAngle",
        "nodes[4].extensions.KHR_lights_punctual",
    ]
    assert scene.light_count == 2  # the point light and the clamped spot


def write_png(path, texels):
    assert oiio.ImageBuf(np.ascontiguousarray(texels, np.uint8)).write(str(path))


def emissive_gltf(tmp_path, emissive, name="glow.gltf", texture=None, double_sided=False):
    """A 1 m square facing +z at z = 0 (UVs: the image upright seen from +z), its material
    emissive, exported by trimesh; `texture` (a PNG file name) becomes its
    `emissiveTexture`."""
    quad = trimesh.Trimesh(
        vertices=[[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]],
        faces=[[0, 1, 2], [0, 2, 3]],
        process=False,
    )
    mat = PBRMaterial(
        name="glow",
        baseColorFactor=[0.0, 0.0, 0.0, 1.0],
        metallicFactor=0.0,
        emissiveFactor=emissive,
        doubleSided=double_sided,
    )
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]  # glTF's v runs down: this flips the image
    quad.visual = trimesh.visual.TextureVisuals(uv=uv, material=mat)
    doc = export_gltf(trimesh.Scene(quad), tmp_path, name)
    if texture:
        doc["images"] = [{"uri": texture}]
        doc["textures"] = [{"source": 0}]
        doc["materials"][0]["emissiveTexture"] = {"index": 0}
    (tmp_path / name).write_text(json.dumps(doc))
    return name


def facing(tmp_path, mesh, z=2.0, size=8):
    desc = {
        "camera": {"position": [0, 0, z], "look_at": [0, 0, 0], "fov": 10,
                   "width": size, "height": size},
        "objects": [{"shape": {"type": "mesh", "file": mesh}}],
    }  # fmt: skip
    path = tmp_path / f"facing{z}.json"
    path.write_text(json.dumps(desc))
    return path


def test_gltf_emissive_factor_and_strength(tmp_path):
    mesh = emissive_gltf(tmp_path, [1.0, 0.5, 0.25])
    doc = json.loads((tmp_path / mesh).read_text())
    doc["materials"][0]["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}
    doc.setdefault("extensionsUsed", []).append("KHR_materials_emissive_strength")
    (tmp_path / mesh).write_text(json.dumps(doc))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        front = gi.render(gi.load_scene(facing(tmp_path, mesh)), "path", spp=2, seed=1)
        back = gi.render(gi.load_scene(facing(tmp_path, mesh, z=-2)), "path", spp=2, seed=1)
    # Seen from the front the pixels are the emitted radiance: factor × strength, W·sr⁻¹·m⁻².
    assert np.allclose(front.radiance[4, 4], [4.0, 2.0, 1.0], rtol=1e-4)
    # One-sided (not doubleSided): the back face is black (its base colour is black).
    assert np.allclose(back.radiance[4, 4], 0.0)


def test_gltf_emissive_texture_double_sided(tmp_path):
    texels = np.zeros((8, 8, 3), np.uint8)
    texels[:, :4] = [255, 128, 0]  # left half orange, right half black
    write_png(tmp_path / "glow.png", texels)
    mesh = emissive_gltf(tmp_path, [2.0, 2.0, 2.0], texture="glow.png", double_sided=True)
    path = facing(tmp_path, mesh, z=-2, size=16)
    desc = json.loads(path.read_text())
    desc["camera"]["fov"] = 40
    path.write_text(json.dumps(desc))
    r = gi.Renderer(gi.load_scene(path), "path", spp=2, seed=1)
    assert r.describe("material", f"{mesh}:glow")["two_sided"] is True
    # Seen from behind (doubleSided: the back emits too), the image's left half is on the
    # right. The texture is sRGB: 128 decodes to 0.2158.
    # Pixels away from the quad's edges (columns ~2.5-13.5): the texture repeats (glTF's
    # default sampler), so bilinear filtering within half a texel of an edge blends in the
    # opposite side's texels.
    out = r.render().radiance
    right, left = out[8, 11], out[8, 5]
    assert np.allclose(right, [2.0, 2.0 * 0.21586, 0.0], rtol=0.01), right
    assert np.allclose(left, 0.0, atol=1e-6), left


def test_gltf_scene_with_lights_and_emitters_renders_lit(tmp_path):
    """What Blender exports: a floor, a sun, a point lamp and an emissive panel in one
    file; everything gi reads, with no warning, and the floor is lit by each."""
    lights = [
        {"type": "directional", "intensity": 683 * 2, "name": "sun"},
        {"type": "point", "intensity": 683, "color": [1, 0.9, 0.8], "name": "lamp"},
    ]
    nodes = [
        {"rotation": DOWN, "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"translation": [1, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
    ]
    floor = plane_gltf(tmp_path, lights, nodes, name="floor.gltf")
    panel = emissive_gltf(tmp_path, [1.0, 1.0, 1.0], name="panel.gltf")
    doc = json.loads((tmp_path / panel).read_text())
    doc["materials"][0] = {**doc["materials"][0], "emissiveFactor": [1, 1, 1],
                           "extensions": {"KHR_materials_emissive_strength":
                                          {"emissiveStrength": 5}}}  # fmt: skip
    (tmp_path / panel).write_text(json.dumps(doc))
    desc = {
        "camera": {"position": [0, 3, 4], "look_at": [0, 0, 0], "width": 32, "height": 24},
        "objects": [
            {"shape": {"type": "mesh", "file": floor}},
            {"shape": {"type": "mesh", "file": panel},
             "transform": {"rotate": [90, 0, 0], "translate": [-1, 0.5, 0]}},
        ],
    }  # fmt: skip
    (tmp_path / "blender.json").write_text(json.dumps(desc))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = gi.load_scene(tmp_path / "blender.json")
        r = gi.Renderer(scene, "path", spp=8, seed=2)
    assert scene.light_count == 2
    assert r.describe("light", 0)["irradiance"] == pytest.approx([2, 2, 2])
    assert r.describe("light", 0)["direction"] == pytest.approx([0, -1, 0], abs=1e-6)
    assert r.describe("light", 1)["intensity"] == pytest.approx([1, 0.9, 0.8])
    assert r.describe("material", "panel.gltf:glow")["emission"] == pytest.approx([5, 5, 5])
    lit = r.render().radiance
    # The sun alone gives the floor ρ/π · 2 W/m² (the base colour factor 0.5).
    floor_sun = ALBEDO / math.pi * 2
    assert np.isfinite(lit).all() and lit.mean() > 0.5 * floor_sun
    for i, off in ((0, {"irradiance": [0, 0, 0]}), (1, {"intensity": [0, 0, 0]})):
        before = r.render(seed=3).radiance.mean()
        r.update(lights={i: off})
        assert r.render(seed=3).radiance.mean() < before
    r.update(materials={"panel.gltf:glow": {"emission": [0, 0, 0]}})
    dark = r.render(seed=3).radiance
    assert dark.max() == pytest.approx(0.0, abs=1e-6)


def test_obj_mtl_emission(tmp_path):
    (tmp_path / "lamp.mtl").write_text(
        "newmtl lamp\nKd 0 0 0\nKe 2 3 4\nnewmtl screen\nKd 0 0 0\nKe 1 1 1\nmap_Ke s.png\n"
    )
    write_png(tmp_path / "s.png", np.full((2, 2, 3), [255, 0, 255]))
    lines = ["mtllib lamp.mtl", "v -1 -0.5 0", "v 0 -0.5 0", "v 0 0.5 0", "v -1 0.5 0"]
    lines += ["v 0 -0.5 0", "v 1 -0.5 0", "v 1 0.5 0", "v 1 0.5 0", "v 0 0.5 0"]
    lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
    lines += ["usemtl lamp", "f 1/1 2/2 3/3", "f 1/1 3/3 4/4"]
    lines += ["usemtl screen", "f 5/1 6/2 7/3", "f 5/1 7/3 9/4"]
    (tmp_path / "lamp.obj").write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = gi.load_scene(facing(tmp_path, "lamp.obj", z=-8, size=16))
    r = gi.Renderer(scene, "path", spp=2, seed=1)
    assert r.describe("material", "lamp.obj:lamp")["two_sided"] is True
    img = r.render().radiance
    # Seen from behind (MTL emitters are two-sided): the `lamp` half (x < 0) on the right.
    assert np.allclose(img[8, 12], [2, 3, 4], rtol=1e-4)
    assert np.allclose(img[8, 3], [1, 0, 1], rtol=1e-3)


MITSUBA = """<scene version="3.0.0">
<sensor type="perspective"><float name="fov" value="{fov}"/>
<transform name="to_world"><lookat origin="0, 5, 0.001" target="0, 0, 0" up="0, 0, -1"/></transform>
<film type="hdrfilm"><integer name="width" value="9"/><integer name="height" value="9"/></film>
</sensor>
<bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
{body}
</scene>"""


def test_mitsuba_directional_emitter(tmp_path):
    # A rectangle facing +y under a sun travelling along (1, -1, 0)/√2 with 3 W/m²: the
    # plane gets 3 cos 45°; from `to_world` (+z mapped to the direction) likewise.
    plane = (
        '<shape type="rectangle"><transform name="to_world"><scale value="10"/>'
        '<rotate x="1" angle="-90"/></transform><ref id="grey"/></shape>'
    )
    for sun in (
        '<emitter type="directional"><vector name="direction" x="1" y="-1" z="0"/>'
        '<rgb name="irradiance" value="3, 3, 3"/></emitter>',
        '<emitter type="directional"><transform name="to_world">'
        '<lookat origin="0, 0, 0" target="1, -1, 0"/></transform>'
        '<float name="irradiance" value="3"/></emitter>',
    ):
        path = tmp_path / "sun.xml"
        path.write_text(MITSUBA.format(fov=1, body=plane + sun))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            scene = gi.load_scene(path)
        r = gi.render(scene, "path", spp=2, max_depth=1, seed=1)
        want = 0.5 / math.pi * 3 * math.cos(math.radians(45))
        assert np.allclose(r.radiance[4, 4], want, rtol=1e-3), r.radiance[4, 4]


@pytest.mark.parametrize("shape", ["rectangle", "cube", "sphere", "obj"])
def test_mitsuba_area_emitter_on_any_shape(tmp_path, shape):
    trimesh.creation.box().export(tmp_path / "box.obj")
    filename = '<string name="filename" value="box.obj"/>' if shape == "obj" else ""
    body = (
        f'<shape type="{shape}" id="lamp">{filename}<transform name="to_world">'
        '<rotate x="1" angle="-90"/><scale value="0.5"/></transform><ref id="grey"/>'
        '<emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>'
    )
    path = tmp_path / "area.xml"
    path.write_text(MITSUBA.format(fov=2, body=body))
    scene = gi.load_scene(path)
    r = gi.Renderer(scene, "path", spp=2, seed=1)
    lamp = r.describe("material", "lamp")
    assert lamp["emission"] == [1, 2, 3] and "two_sided" not in lamp
    assert lamp["diffuse"] == [0.5, 0.5, 0.5]  # its BSDF's, and `grey` itself stays dark
    assert "emission" not in r.describe("material", "grey")
    # Seen from above, the emitter's front (outside, or the rectangle's +z turned to +y)
    # shows its radiance.
    assert np.allclose(r.render().radiance[4, 4], [1, 2, 3], rtol=1e-4)


def test_mitsuba_area_emitter_is_one_sided_and_reads_bitmaps(tmp_path):
    img = np.full((4, 4, 3), 0.5, np.float32)
    img[:2] = [6, 3, 0]  # the top half bright
    oiio.ImageBuf(img).write(str(tmp_path / "glow.exr"))
    body = (
        '<shape type="rectangle" id="down"><transform name="to_world">'
        '<rotate x="1" angle="90"/></transform><ref id="grey"/>'
        '<emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>'
    )
    path = tmp_path / "one.xml"
    path.write_text(MITSUBA.format(fov=2, body=body))
    dark = gi.render(gi.load_scene(path), "path", spp=2, seed=1).radiance[4, 4]
    assert np.allclose(dark, 0.0, atol=1e-6), "the rectangle faces away from the camera"
    body = (
        '<shape type="rectangle" id="up"><transform name="to_world">'
        '<rotate x="1" angle="-90"/></transform><ref id="grey"/>'
        '<emitter type="area"><texture type="bitmap" name="radiance">'
        '<string name="filename" value="glow.exr"/></texture></emitter></shape>'
    )
    path.write_text(MITSUBA.format(fov=25, body=body))
    scene = gi.load_scene(path)
    r = gi.Renderer(scene, "path", spp=2, seed=1)
    assert r.describe("material", "up")["emission"] == [6, 6, 6]  # the texture's peak
    out = r.render().radiance
    # Mitsuba's rectangle has v up +y, so the image's first (bright) rows lie along y = -1
    # (Mitsuba 3.9.1 shows a bitmap upside down on it, checked); turned to face +y, y = -1
    # goes to +z, which the camera above sees at the image's bottom: the bright row there.
    assert np.allclose(out[6, 4], [6, 3, 0], rtol=0.01), out[6, 4]
    assert np.allclose(out[2, 4], [0.5, 0.5, 0.5], rtol=0.01), out[2, 4]


@pytest.mark.parametrize("method", gi.methods())
def test_mitsuba_constant_and_envmap_load_for_every_method(tmp_path, method):
    """The environment emitters load and render in every method (`ispm`'s photons leave the
    sky and its GPU direct light samples it, as `direct`'s), or are refused by the core with
    a `SettingError` naming the method."""
    oiio.ImageBuf(np.full((4, 8, 3), 0.5, np.float32)).write(str(tmp_path / "sky.exr"))
    for sky in (
        '<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>',
        '<emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>',
    ):
        path = tmp_path / "sky.xml"
        cube = '<shape type="cube"><ref id="grey"/></shape>'
        path.write_text(MITSUBA.format(fov=40, body=cube + sky))
        scene = gi.load_scene(path)
        photons = {"photons": 1000} if method in ("photon", "gather", "ispm") else {}
        try:
            r = gi.Renderer(scene, method, size=(8, 8), spp=1, **photons)
        except gi.SettingError as e:
            assert method in str(e) and "environment" in str(e)
            continue
        img = r.render().radiance
        assert np.isfinite(img).all() and img.mean() > 0.1


# -- the scene format through updates, describe and animation --------------------------------


def room(tmp_path, extra=None):
    desc = json.loads(gi.builtin_json("cornell"))
    desc["materials"]["lamp"] = {"diffuse": [0.8, 0.8, 0.8], "emission": [10, 10, 10]}
    desc["objects"].append(
        {"name": "panel", "shape": {"type": "quad", "size": [0.4, 0.4]}, "material": "lamp",
         "transform": {"translate": [0, 1.98, 0], "rotate": [180, 0, 0]}}
    )  # fmt: skip
    desc.update(extra or {})
    path = tmp_path / "room.json"
    path.write_text(json.dumps(desc))
    return gi.load_scene(path)


def test_update_and_describe_emission_and_directional_lights(tmp_path):
    r = gi.Renderer(room(tmp_path), "path", size=(24, 24), spp=4, seed=1)
    lamp = r.describe("material", "lamp")
    assert lamp["emission"] == [10, 10, 10] and "two_sided" not in lamp
    r.update(materials={"lamp": {"emission": [0, 0, 0]}}, lights={0: {"intensity": [0, 0, 0]}})
    assert r.render(seed=5).radiance.mean() == 0.0
    r.update(materials={"lamp": {"emission": [10, 10, 10]}})
    panel = r.render(seed=5).radiance.mean()
    assert panel > 0
    # Twice the radiance, and the back face (towards the ceiling) emits too.
    r.update(materials={"lamp": {"emission": [20, 20, 20], "two_sided": True}})
    assert r.describe("material", "lamp")["two_sided"] is True
    assert r.render(seed=5).radiance.mean() > 1.5 * panel
    # A light's type changes with the fields the new type needs.
    sun = {"type": "directional", "direction": [0.2, -1, 0.1], "irradiance": [2, 2, 2],
           "angular_diameter": 1}  # fmt: skip
    r.update(lights={0: sun}, materials={"lamp": {"emission": [0, 0, 0]}})
    got = r.describe("light", 0)
    assert got["type"] == "directional" and got["irradiance"] == [2, 2, 2]
    assert got["angular_diameter"] == pytest.approx(1.0, abs=1e-3)  # f32 cos and acos
    assert np.linalg.norm(got["direction"]) == pytest.approx(1.0)
    r.update(lights={0: {"irradiance": [3, 3, 3]}})
    assert r.describe("light", 0)["irradiance"] == [3, 3, 3]
    with pytest.raises(gi.SceneError, match="irradiance"):
        r.update(lights={0: {"irradiance": [-1, 0, 0]}})
    with pytest.raises(gi.SceneError, match="emission"):
        r.update(materials={"lamp": {"emission": [float("nan"), 0, 0]}})
    with pytest.raises(gi.SceneError):
        r.update(lights={0: {"type": "point"}})  # a point light needs a position
    assert r.describe("light", 0)["type"] == "directional"


def test_animation_tracks_animate_emission_and_the_sun(tmp_path):
    sun = {"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}
    anim = {
        "tracks": [
            {"target": "material", "name": "lamp", "keys": [
                {"time": 0, "value": {"emission": [0, 0, 0]}},
                {"time": 2, "value": {"emission": [10, 5, 0]}}]},
            {"target": "light", "index": 1, "keys": [
                {"time": 0, "value": {"irradiance": [1, 1, 1], "angular_diameter": 0}},
                {"time": 2, "value": {"irradiance": [3, 3, 3], "angular_diameter": 2}}]},
        ]
    }  # fmt: skip
    desc = json.loads(gi.builtin_json("cornell"))
    scene = room(tmp_path, {"lights": [*desc["lights"], sun], "animation": anim})
    at = gi.animation_updates(scene, 1.0)
    assert at["materials"]["lamp"]["emission"] == pytest.approx([5, 2.5, 0])
    assert at["lights"][1]["irradiance"] == pytest.approx([2, 2, 2])
    assert at["lights"][1]["angular_diameter"] == pytest.approx(1)
    r = gi.Renderer(scene, "path", size=(16, 16), spp=1)
    frames = list(r.render_animation([0, 30], fps=30))
    assert [n for n, _ in frames] == [0, 30]
    assert r.describe("material", "lamp")["emission"] == pytest.approx([5, 2.5, 0])
    assert r.describe("light", 1)["irradiance"] == pytest.approx([2, 2, 2])
    anim["tracks"][0]["keys"][1]["value"]["emission"] = [-1, 0, 0]
    with pytest.raises(gi.SceneError, match="emission"):
        room(tmp_path, {"lights": [*desc["lights"], sun], "animation": anim})
