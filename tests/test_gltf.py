"""glTF as users bring it: tangent frames (stored TANGENT with its handedness, MikkTSpace's
when absent) shading normal maps alike on the CPU and the GPU, KHR_texture_transform,
KHR_mesh_quantization, Draco-compressed meshes, and the occlusion map said once. The assets
are written by ``tests/gltf_assets.py``.

The normal-map test has an analytic reference: a quad of round bumps under a directional
light from the upper right, one bounce; the ratio of the bumps' upper-right to lower-right
quadrants is that of Lambert's cosine over the map's normals (1.1435, computed here), and a
tangent frame with the wrong handedness turns it below 1."""

import json
import sys
import warnings

import numpy as np
import pytest
from gltf_assets import bump_normals, draco_sphere, normal_mapped_quad, textured_quad

import gi
import gi.gltf as gltf_module
from gi.gltf import read_gltf

SIZE = 64
LIGHT = np.array([0.5, 0.5, 0.7071]) / np.linalg.norm([0.5, 0.5, 0.7071])


def quad_scene(tmp_path, glb, light=True):
    """The asset seen straight on (the 2×2 m quad fills the 64×64 image), lit by a sun from
    the upper right (``LIGHT``), as a JSON scene naming the file."""
    desc = {
        "camera": {
            "position": [0, 0, 3],
            "look_at": [0, 0, 0],
            "fov": 2 * np.degrees(np.arctan(1 / 3)),
            "width": SIZE,
            "height": SIZE,
        },
        "lights": [{"type": "directional", "direction": (-LIGHT).tolist(), "irradiance": [3] * 3}]
        if light
        else [],
        "objects": [{"shape": {"type": "mesh", "file": glb.name}}],
    }
    path = tmp_path / f"{glb.stem}.json"
    path.write_text(json.dumps(desc))
    return path


def quadrants(img):
    """Mean of the bumps' upper-right, lower-right and upper-left quadrants (4×4 bumps of
    16×16 pixels; 2 pixels left out along each cell's axes)."""
    yy, xx = np.mgrid[0:SIZE, 0:SIZE]
    fx, fy = xx % 16 - 7.5, -(yy % 16 - 7.5)
    return [img[(sx * fx > 2) & (sy * fy > 2)].mean() for sx, sy in ((1, 1), (1, -1), (-1, 1))]


def analytic_ratio():
    """Upper-right over lower-right of Lambert's cosine max(0, n·l) over the map's normals
    (the map evaluated 8× finer than the pixels, box-filtered)."""
    n = bump_normals(n=SIZE * 8) * 2 - 1
    img = np.clip(n @ LIGHT, 0, None).reshape(SIZE, 8, SIZE, 8).mean(axis=(1, 3))
    ur, lr, _ = quadrants(img)
    return ur / lr


def render_quad(tmp_path, method, **asset):
    name = "q_" + "_".join(f"{k}-{v}" for k, v in asset.items())
    glb = normal_mapped_quad(tmp_path / f"{name}.glb", **asset)
    scene = gi.load_scene(quad_scene(tmp_path, glb))
    if method == "path":
        r = gi.render(scene, "path", spp=16, max_depth=1, seed=1)
    else:
        r = gi.render(scene, method, spp=4)
    return r.radiance.mean(axis=2)


@pytest.mark.parametrize(
    "asset",
    [
        {},
        {"tangents": "none"},
        {"mirror_u": True},
        {"mirror_u": True, "tangents": "none"},
        {"quantized": True},
    ],
    ids=["stored", "mikktspace", "mirrored-stored", "mirrored-mikktspace", "quantized"],
)
def test_normal_mapped_bumps_shade_as_their_normals_say(tmp_path, asset):
    """Stored tangents, MikkTSpace's, a mirrored map (w = −1) and quantized attributes all
    give the analytic shading of the bumps, on the CPU (`path`) and the GPU (`direct`):
    the upper-right/lower-right ratio within 1% of 1.1435, upper-right/upper-left the
    same by symmetry, and the GPU image within 2% of the CPU's pixel by pixel (mean)."""
    expected = analytic_ratio()
    assert expected == pytest.approx(1.1435, abs=1e-3)
    cpu = render_quad(tmp_path, "path", **asset)
    gpu = render_quad(tmp_path, "direct", **asset)
    for img in (cpu, gpu):
        ur, lr, ul = quadrants(img)
        assert ur / lr == pytest.approx(expected, rel=0.01)
        assert ur / ul == pytest.approx(expected, rel=0.01)
    assert np.abs(gpu - cpu).mean() < 0.02 * cpu.mean()


QUARTER_TURN = {"rotation": float(np.pi / 2)}


@pytest.mark.parametrize("tangents", ["stored", "none"])
def test_rotated_normal_map_keeps_the_bumps_shading(tmp_path, tangents):
    """KHR_texture_transform turning the normal map a quarter (its round bumps land on the
    same cells) leaves the shading of the bumps as it was, with stored tangents turned with
    the UVs as with MikkTSpace's (generated from the turned UVs): the upper-right/lower-right
    ratio within 1% of the analytic 1.1435 on the CPU and the GPU. Tangents left as stored
    (the frame a quarter off) light the bumps' lower-right sides: the ratio falls below 1."""
    expected = analytic_ratio()
    for method in ("path", "direct"):
        img = render_quad(tmp_path, method, tangents=tangents, transform=QUARTER_TURN)
        ur, lr, ul = quadrants(img)
        assert ur / lr == pytest.approx(expected, rel=0.01), method
        assert ur / ul == pytest.approx(expected, rel=0.01), method


def test_stored_tangents_turn_with_the_texture_transform(tmp_path, monkeypatch):
    """The read tangents are ∂P/∂u' of the turned UVs: for u' = cos r·u + sin r·v on the
    quad (u along +x, v along −y) that is (cos r, −sin r, 0), handedness unchanged by a
    rotation and flipped by a mirroring scale; with the turn not applied (the reader's
    tangents as stored) the quarter-turned bumps shade wrongly."""
    r = 0.4
    glb = normal_mapped_quad(tmp_path / "r.glb", transform={"rotation": r})
    prim = read_gltf(glb).meshes[0][0]
    np.testing.assert_allclose(prim.tangents, np.tile([np.cos(r), -np.sin(r), 0, -1], (4, 1)))
    glb = normal_mapped_quad(tmp_path / "m.glb", transform={"scale": [-1.0, 1.0]})
    np.testing.assert_allclose(
        read_gltf(glb).meshes[0][0].tangents, np.tile([-1.0, 0, 0, 1.0], (4, 1)), atol=1e-12
    )
    monkeypatch.setattr(gltf_module, "transform_tangents", lambda t, n, m: t)
    ur, lr, _ = quadrants(render_quad(tmp_path, "path", transform=QUARTER_TURN))
    assert ur / lr < 1 / 1.05


def test_wrong_handedness_inverts_the_bumps(tmp_path):
    """The regions the test above reads tell a wrong frame: stored tangents with w negated
    (a reader that ignores handedness) light the bumps' lower sides instead."""
    for method in ("path", "direct"):
        ur, lr, _ = quadrants(render_quad(tmp_path, method, tangents="wrong-w"))
        assert ur / lr < 1 / 1.1, method


def test_stored_tangents_are_read_without_a_warning(tmp_path):
    glb = normal_mapped_quad(tmp_path / "q.glb")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gi.load_scene(quad_scene(tmp_path, glb))
    prim = read_gltf(glb).meshes[0][0]
    # glTF's w = +1 (bitangent up the image) is gi's −1 (its bitangent runs along +v).
    np.testing.assert_array_equal(prim.tangents, np.tile([1.0, 0, 0, -1.0], (4, 1)))


def test_quantized_attributes_read_as_the_float_ones(tmp_path):
    a = read_gltf(normal_mapped_quad(tmp_path / "f.glb")).meshes[0][0]
    b = read_gltf(normal_mapped_quad(tmp_path / "q.glb", quantized=True)).meshes[0][0]
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_allclose(a.normals, b.normals, atol=1 / 127)
    np.testing.assert_allclose(a.uvs, b.uvs, atol=1 / 65535)
    np.testing.assert_allclose(a.tangents, b.tangents, atol=1 / 127)


TRANSFORM = {"offset": [0.25, -0.1], "rotation": 0.4, "scale": [2.0, 1.5]}


def transform_matrix(t):
    c, s = np.cos(t["rotation"]), np.sin(t["rotation"])
    tr = np.array([[1, 0, t["offset"][0]], [0, 1, t["offset"][1]], [0, 0, 1.0]])
    rot = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1.0]])
    return tr @ rot @ np.diag([*t["scale"], 1.0])


def test_texture_transform_is_the_transformed_uvs(tmp_path):
    """KHR_texture_transform (offset, rotation, scale) reads as the extension's matrix
    T·R·S applied to TEXCOORD_0: the same texture coordinates, and the same image, as the
    quad whose stored UVs are transformed."""
    m = transform_matrix(TRANSFORM)
    a = textured_quad(tmp_path / "ext.glb", transform=TRANSFORM)
    b = textured_quad(tmp_path / "baked.glb", uv_matrix=m)
    np.testing.assert_allclose(read_gltf(a).meshes[0][0].uvs, read_gltf(b).meshes[0][0].uvs, 1e-6)
    imgs = []
    for glb in (a, b):
        scene = gi.load_scene(quad_scene(tmp_path, glb))
        imgs.append(gi.render(scene, "path", spp=4, max_depth=1, seed=2).radiance)
    np.testing.assert_allclose(imgs[0], imgs[1], atol=1e-4)
    # And the transform changes the picture (the test would see it ignored).
    plain = gi.load_scene(quad_scene(tmp_path, textured_quad(tmp_path / "plain.glb")))
    other = gi.render(plain, "path", spp=4, max_depth=1, seed=2).radiance
    assert np.abs(other - imgs[0]).mean() > 0.05 * imgs[0].mean()


def test_textures_of_one_material_with_different_transforms_are_an_error(tmp_path):
    glb = textured_quad(tmp_path / "t.glb", transform=TRANSFORM)
    # A second texture (the normal map slot) on the same image, without the transform.
    import struct

    data = glb.read_bytes()
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + n])
    doc["materials"][0]["normalTexture"] = {"index": 0}
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + n :]
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + rest
    glb.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
    with pytest.raises(gi.SceneError, match=r"materials\[0\].normalTexture.*one texture transform"):
        gi.load_scene(glb)


def test_draco_compressed_mesh_loads_as_the_plain_one(tmp_path):
    """KHR_draco_mesh_compression through DracoPy: the same triangles and (14-bit
    quantized) vertices as the uncompressed file, and the same image within 0.5%."""
    import DracoPy  # noqa: F401  (the `test` extra installs it: never skipped)

    plain = read_gltf(draco_sphere(tmp_path / "plain.glb", compressed=False)).meshes[0][0]
    packed = read_gltf(draco_sphere(tmp_path / "draco.glb")).meshes[0][0]
    assert len(packed.faces) == len(plain.faces)
    np.testing.assert_allclose(packed.vertices, plain.vertices, atol=2.0 / 2**14)
    means = []
    for name in ("plain", "draco"):
        scene = gi.load_scene(quad_scene(tmp_path, tmp_path / f"{name}.glb"))
        means.append(gi.render(scene, "path", spp=16, max_depth=1, seed=3).radiance.mean())
    assert means[1] == pytest.approx(means[0], rel=0.005)


def test_draco_without_the_decoder_names_the_extension_and_the_fix(tmp_path, monkeypatch):
    import DracoPy  # noqa: F401  (the `test` extra installs it: never skipped)

    glb = draco_sphere(tmp_path / "draco.glb")
    monkeypatch.setitem(sys.modules, "DracoPy", None)  # import fails
    with pytest.raises(gi.SceneError, match="KHR_draco_mesh_compression") as e:
        gi.load_scene(glb)
    assert "pip install DracoPy" in str(e.value) and "gltf-transform" in str(e.value)


def test_occlusion_maps_are_explained_once(tmp_path):
    glb = textured_quad(tmp_path / "t.glb")
    doc_bytes = glb.read_bytes()
    import struct

    n = struct.unpack_from("<I", doc_bytes, 12)[0]
    doc = json.loads(doc_bytes[20 : 20 + n])
    doc["materials"][0]["occlusionTexture"] = {"index": 0}
    doc["materials"].append(dict(doc["materials"][0], name="second"))
    doc["meshes"][0]["primitives"].append(dict(doc["meshes"][0]["primitives"][0], material=1))
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + doc_bytes[20 + n :]
    glb.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
    with pytest.warns(gi.AssetWarning) as record:
        gi.load_scene(quad_scene(tmp_path, glb))
    occlusion = [w for w in record if "occlusion" in str(w.message)]
    assert len(occlusion) == 1
    assert "ambient-occlusion map would darken" in str(occlusion[0].message)
