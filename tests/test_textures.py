"""Textures and UVs: base colour, alpha cut-outs and normal maps from glTF, OBJ+MTL and gi's
JSON scenes render the same in `direct`, `ispm` and `path`. Every file is written here as
exporters write them: PNGs by OpenImageIO (8-bit sRGB), glTF JSON with a binary buffer,
OBJ text with `vt` and an MTL."""

import json
import warnings

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)
import pytest

import gi

METHODS = ("direct", "ispm", "path")
SIZE = (48, 48)
RED, BLUE = np.array([0.8, 0.1, 0.1]), np.array([0.1, 0.1, 0.8])


def srgb_encode(c):
    c = np.clip(c, 0, 1)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def write_png(path, rgba, srgb=True):
    """Float RGBA (H, W, 4) in [0, 1] as an 8-bit PNG (colour sRGB-encoded, alpha linear)."""
    img = np.ascontiguousarray(rgba, np.float64).copy()
    if srgb:
        img[..., :3] = srgb_encode(img[..., :3])
    h, w, c = img.shape
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(w, h, c, oiio.UINT8))
    assert out.write_image(np.ascontiguousarray(np.round(img * 255).astype(np.uint8)))
    out.close()


def checker(n=8, cell=2, a=RED, b=BLUE):
    """n×n texels, cells of `cell` texels: colour a where (i + j) is even."""
    idx = np.arange(n) // cell
    even = (idx[:, None] + idx[None, :]) % 2 == 0
    rgb = np.where(even[..., None], a, b)
    return np.concatenate([rgb, np.ones((n, n, 1))], axis=2)


def write_gltf(path, image, material_extra=None, pbr_extra=None):
    """A 2×2 quad in the xz plane (normal +y, u along +x, v along +z) with a base-colour
    texture `image` (a file name next to it), metallic 0."""
    pos = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], np.float32)
    nrm = np.tile(np.array([0, 1, 0], np.float32), (4, 1))
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    idx = np.array([0, 2, 1, 0, 3, 2], np.uint16)  # counter-clockwise seen from +y
    blob = pos.tobytes() + nrm.tobytes() + uv.tobytes() + idx.tobytes()
    (path.parent / f"{path.stem}.bin").write_bytes(blob)
    views, accessors, offset = [], [], 0
    for arr, kind, comp in ((pos, "VEC3", 5126), (nrm, "VEC3", 5126), (uv, "VEC2", 5126)):
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": arr.nbytes})
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": 4, "type": kind}
        if arr is pos:
            acc["min"], acc["max"] = pos.min(0).tolist(), pos.max(0).tolist()
        accessors.append(acc)
        offset += arr.nbytes
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": idx.nbytes})
    accessors.append({"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"})
    pbr = {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0}
    material = {"name": "checker", "pbrMetallicRoughness": {**pbr, **(pbr_extra or {})}}
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                        "indices": 3,
                        "material": 0,
                    }
                ]
            }
        ],
        "materials": [{**material, **(material_extra or {})}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": image}],
        "buffers": [{"uri": f"{path.stem}.bin", "byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    path.write_text(json.dumps(doc))


def top_down_scene(tmp_path, objects, light=(0, 2, 0), materials=None, height=2.5):
    desc = {
        "camera": {
            "position": [0, height, 0],
            "look_at": [0, 0, 0],
            "up": [0, 0, -1],
            "fov": 50,
        },
        "lights": [{"type": "point", "position": list(light), "intensity": [4, 4, 4]}],
        "materials": materials or {"white": {"diffuse": [0.8, 0.8, 0.8]}},
        "objects": objects,
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(desc))
    return path


def render(path, method, **kw):
    settings = {"spp": 16, "size": SIZE, "seed": 3, **kw}
    if method == "ispm":
        settings["photons"] = 20_000
    return gi.render(gi.load_scene(path), method, **settings)


def test_textured_gltf_renders_its_texture_alike_in_all_methods(tmp_path):
    write_png(tmp_path / "checker.png", checker())
    write_gltf(tmp_path / "quad.gltf", "checker.png")
    scene = top_down_scene(tmp_path, [{"shape": {"type": "mesh", "file": "quad.gltf"}}])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the texture is read, not reported
        results = {m: render(scene, m) for m in METHODS}
    # Pixel classes from the albedo AOV of the path tracer (the texture at the pixel
    # centre): where bilinear filtering mixes neighbouring cells (within a texel, about
    # 5 pixels, of a cell edge) the albedo drops below 0.75, and those pixels are left out.
    albedo = results["path"].albedo
    red = albedo[..., 0] > 0.75
    blue = albedo[..., 2] > 0.75
    assert red.sum() > 100 and blue.sum() > 100, (red.sum(), blue.sum())
    means = {m: (r.radiance[red].mean(0), r.radiance[blue].mean(0)) for m, r in results.items()}
    for m, (r, b) in means.items():
        # The texture shows: red cells are red, blue cells blue, in the texture's ratio
        # (0.8 / 0.1 per channel; 8-bit sRGB storage keeps it within 2%).
        assert r[0] / r[2] > 5 and b[2] / b[0] > 5, (m, r, b)
        assert r[0] / b[2] == pytest.approx(1.0, rel=0.15), (m, r, b)
    # The three agree: class means within 5% (the single quad under a point light has no
    # indirect light, so the methods differ only by sampling: the path tracer's pixel jitter
    # at 16 spp and the raster methods' 16 sub-pixel samples, well under 1% here).
    ref_r, ref_b = means["path"]
    for m in ("direct", "ispm"):
        r, b = means[m]
        np.testing.assert_allclose(r[0], ref_r[0], rtol=0.05, err_msg=m)
        np.testing.assert_allclose(b[2], ref_b[2], rtol=0.05, err_msg=m)
    # And the albedo AOVs of the raster methods (from the G-buffer) show the same cells.
    for m in ("direct", "ispm"):
        a = results[m].albedo
        assert (a[red][:, 0] > 0.5).mean() > 0.95 and (a[blue][:, 2] > 0.5).mean() > 0.95, m


def test_obj_mtl_map_kd_is_upright(tmp_path):
    """An OBJ quad facing +z with a texture red on its top half, blue below: OBJ's v runs up
    the image, so the top of the image must be red."""
    img = np.ones((8, 8, 4))
    img[:4, :, :3] = RED
    img[4:, :, :3] = BLUE
    write_png(tmp_path / "tb.png", img)
    (tmp_path / "quad.mtl").write_text("newmtl tex\nKd 1 1 1\nmap_Kd tb.png\n")
    (tmp_path / "quad.obj").write_text(
        "mtllib quad.mtl\n"
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "vn 0 0 1\n"
        "usemtl tex\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
    )
    desc = {
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 50},
        "lights": [{"type": "point", "position": [0, 0, 3], "intensity": [5, 5, 5]}],
        "objects": [{"shape": {"type": "mesh", "file": "quad.obj"}}],
    }
    (tmp_path / "s.json").write_text(json.dumps(desc))
    for method in ("path", "direct"):
        r = render(tmp_path / "s.json", method, size=(32, 32), spp=4)
        top, bottom = r.albedo[4:12, 8:24].mean((0, 1)), r.albedo[20:28, 8:24].mean((0, 1))
        assert top[0] > 0.6 and top[2] < 0.2, (method, top)
        assert bottom[2] > 0.6 and bottom[0] < 0.2, (method, bottom)


def masked_scene(tmp_path, with_quad=True):
    """A white floor at y = 0; above it at y = 1 a 1×1 glTF quad (alphaMode MASK) whose
    texture is transparent on its -x half and opaque green on its +x half; a point light
    up and to the left, so the quad's shadow falls to the right of it."""
    img = np.zeros((8, 8, 4))
    img[..., 1] = 0.8
    img[:, 4:, 3] = 1.0  # u > 0.5 (+x) opaque
    write_png(tmp_path / "mask.png", img)
    write_gltf(
        tmp_path / "masked.gltf",
        "mask.png",
        material_extra={"alphaMode": "MASK", "alphaCutoff": 0.5},
    )
    objects = [{"shape": {"type": "quad", "size": [8, 8]}, "material": "white"}]
    if with_quad:
        objects.append(
            {
                "shape": {"type": "mesh", "file": "masked.gltf"},
                "transform": {"scale": 0.5, "translate": [0, 1, 0]},
            }
        )
    path = top_down_scene(tmp_path, objects, light=(-3, 3, 0), height=4)
    return path


def column_x(col, width=SIZE[0], height=4.0, fov=50):
    """World x seen at the centre of image column `col` on the floor (y = 0)."""
    half = height * np.tan(np.radians(fov / 2))
    return ((col + 0.5) / width * 2 - 1) * half


def test_alpha_masked_quad_is_cut_out_in_all_methods(tmp_path):
    scene = masked_scene(tmp_path)
    (tmp_path / "floor").mkdir()
    floor_only = masked_scene(tmp_path / "floor", with_quad=False)
    x = column_x(np.arange(SIZE[0]))
    rows = slice(SIZE[1] // 2 - 3, SIZE[1] // 2 + 3)  # z near 0
    cut_half = (x > -0.4) & (x < -0.1)
    opaque_half = (x > 0.1) & (x < 0.4)
    # Shadows on the floor from the light at (-3, 3): a point (x, 1) lands at x + (x + 3)/2,
    # so the cut half (x in [-0.5, 0]) would shade [0.75, 1.5] and the opaque half shades
    # [1.5, 2.25]; the quad itself covers floor |x| < 0.67 in the image.
    cut_shadow = (x > 0.8) & (x < 1.4)
    opaque_shadow = (x > 1.6) & (x < 2.1)
    for method in METHODS:
        r = render(scene, method, spp=4)
        ref = render(floor_only, method, spp=4)
        depth = r.depth[rows]
        # See-through: the cut half shows the floor (depth 4), the opaque half the quad (3).
        assert np.allclose(depth[:, cut_half], 4.0, atol=0.05), (method, depth[:, cut_half])
        assert np.allclose(depth[:, opaque_half], 3.0, atol=0.05), method
        assert (r.albedo[rows][:, opaque_half][..., 1] > 0.6).all(), method
        # Cut-out shadow: lit where only the transparent half is between floor and light
        # (within 10%: ISPM's indirect light from the quad's underside, path noise),
        # dark behind the opaque half (what is left is indirect light).
        lum = r.radiance[rows].mean(axis=(0, 2))
        ref_lum = ref.radiance[rows].mean(axis=(0, 2))
        lit = lum[cut_shadow].mean() / ref_lum[cut_shadow].mean()
        dark = lum[opaque_shadow].mean() / ref_lum[opaque_shadow].mean()
        assert lit > 0.9, (method, lit)
        assert dark < 0.2, (method, dark)


def test_alpha_cut_out_in_the_cpu_intersector(tmp_path):
    """Rays through the transparent half pass, through the opaque half they hit."""
    scene = gi.load_scene(masked_scene(tmp_path))
    origins = np.array([[-0.25, 3, 0], [0.25, 3, 0]], np.float32)
    dirs = np.array([[0, -1, 0], [0, -1, 0]], np.float32)
    t, _tri = scene.intersect(origins, dirs)
    np.testing.assert_allclose(t, [3.0, 2.0], atol=1e-4)


def test_normal_map_tilts_the_shading(tmp_path):
    """A JSON-scene quad with a normal map tilting every normal 30° towards +x, lit from +x
    at 45°: Lambert's cosine at the centre rises from cos 45° = 0.707 to cos 15° = 0.966
    (×1.366). A flat map (0.5, 0.5, 1) changes nothing."""
    tilt = np.radians(30)
    n = np.array([np.sin(tilt), 0.0, np.cos(tilt)]) * 0.5 + 0.5
    write_png(tmp_path / "tilt.png", np.broadcast_to([*n, 1.0], (4, 4, 4)), srgb=False)
    write_png(tmp_path / "flat.png", np.broadcast_to([0.5, 0.5, 1.0, 1.0], (4, 4, 4)), srgb=False)
    centre = (slice(20, 28), slice(20, 28))
    out = {}
    for name in ("tilt", "flat"):
        (tmp_path / name).mkdir()
        mats = {"m": {"diffuse": [0.8, 0.8, 0.8], "normal_texture": f"../{name}.png"}}
        objects = [{"shape": {"type": "quad", "size": [2, 2]}, "material": "m"}]
        path = top_down_scene(tmp_path / name, objects, light=(2, 2, 0), materials=mats)
        for method in METHODS:
            out[name, method] = render(path, method, spp=4).radiance[centre].mean()
    for method in METHODS:
        ratio = out["tilt", method] / out["flat", method]
        # Over the 8×8 centre pixels the light direction varies by a few degrees: ±3%.
        assert ratio == pytest.approx(1.366, rel=0.04), (method, ratio)


def test_missing_texture_in_a_json_scene_is_a_scene_error(tmp_path):
    mats = {"m": {"diffuse_texture": "nope.png"}}
    objects = [{"shape": {"type": "quad", "size": [2, 2]}, "material": "m"}]
    path = top_down_scene(tmp_path, objects, materials=mats)
    with pytest.raises(gi.SceneError) as e:
        gi.load_scene(path)
    assert e.value.field == "materials.m.diffuse_texture"


def test_unknown_texture_name_in_a_mesh_material_is_a_scene_error():
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2]], np.uint32)
    mats = json.dumps([["a", {"diffuse_texture": "missing"}]])
    mesh = (verts, faces, None, mats, np.zeros(1, np.uint32), None)
    desc = {
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]},
        "objects": [{"shape": {"type": "mesh", "file": "m"}}],
    }
    with pytest.raises(gi.SceneError, match="no texture named"):
        gi.Scene.from_json(json.dumps(desc), "t", {"m": mesh})


def test_specular_and_roughness_maps_multiply_their_factors(tmp_path):
    """Uniform maps equal constant factors: specular 1 × a 0.5 map and roughness 1 × a 0.2
    map render like specular 0.5, roughness 0.2 (within 2%: the 8-bit sRGB map decodes to
    0.5 ± 0.002, 51/255 = 0.2 exactly), and unlike roughness 1 (the highlight spreads)."""
    write_png(tmp_path / "half.png", np.full((4, 4, 4), 0.5) + [0, 0, 0, 0.5])
    write_png(tmp_path / "r02.png", np.full((4, 4, 4), 0.2) + [0, 0, 0, 0.8], srgb=False)
    base = {"diffuse": [0.2, 0.2, 0.2], "fresnel": False}
    variants = {
        "maps": {
            **base,
            "specular": [1, 1, 1],
            "specular_texture": "../half.png",
            "roughness": 1.0,
            "roughness_texture": "../r02.png",
        },
        "factors": {**base, "specular": [0.5, 0.5, 0.5], "roughness": 0.2},
        "rough": {**base, "specular": [0.5, 0.5, 0.5], "roughness": 1.0},
    }
    out = {}
    for name, mat in variants.items():
        (tmp_path / name).mkdir()
        objects = [{"shape": {"type": "quad", "size": [2, 2]}, "material": "m"}]
        # Light beside the camera: the highlight sits near the image centre.
        path = top_down_scene(tmp_path / name, objects, light=(0.3, 2.5, 0), materials={"m": mat})
        for method in METHODS:
            out[name, method] = render(path, method, spp=4).radiance.mean(axis=2)
    for method in METHODS:
        maps, factors, rough = (out[v, method] for v in variants)
        peak = np.unravel_index(np.argmax(factors), factors.shape)
        window = tuple(slice(max(p - 3, 0), p + 4) for p in peak)
        np.testing.assert_allclose(maps[window].mean(), factors[window].mean(), rtol=0.02)
        np.testing.assert_allclose(maps.mean(), factors.mean(), rtol=0.02)
        assert factors[window].mean() > 1.5 * rough[window].mean(), method


def test_mtl_maps_become_textures(tmp_path):
    """map_Ks, map_Ns, map_d and a height map in map_Bump are read into textures."""
    write_png(tmp_path / "spec.png", np.full((2, 2, 4), 1.0))
    write_png(tmp_path / "ns.png", np.full((2, 2, 4), 1.0), srgb=False)
    grey = np.zeros((4, 4, 3))
    grey[:, 2:] = 1.0
    out = oiio.ImageOutput.create(str(tmp_path / "cut.png"))
    out.open(str(tmp_path / "cut.png"), oiio.ImageSpec(4, 4, 1, oiio.UINT8))
    out.write_image(np.ascontiguousarray((grey[..., :1] * 255).astype(np.uint8)))
    out.close()
    height = np.zeros((8, 8, 4))
    height[..., :3] = np.linspace(0, 1, 8)[None, :, None]  # a ramp along u
    height[..., 3] = 1
    write_png(tmp_path / "h.png", height, srgb=False)
    (tmp_path / "m.mtl").write_text(
        "newmtl a\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 100\n"
        "map_Ks spec.png\nmap_Ns ns.png\nmap_d cut.png\nmap_Bump -bm 2 h.png\n"
    )
    (tmp_path / "q.obj").write_text(
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl a\nf 1/1 2/2 3/3\n"
    )
    from gi.meshes import load_mesh
    from gi.textures import TextureSet

    textures = TextureSet()
    entry = load_mesh(tmp_path / "q.obj", "s", "f", textures)
    [(_, desc)] = json.loads(entry[3])
    assert desc["specular_texture"] in textures.arrays
    # map_Ns: the exponent 100 × 1.0 → roughness (2/102)^(1/4), factor 1.
    rough = textures.arrays[desc["roughness_texture"]]
    assert desc["roughness"] == 1.0
    np.testing.assert_allclose(rough[..., 1], (2 / 102) ** 0.25, rtol=1e-5)
    # map_d of a grey image: coverage is its grey value; cut out below 0.5.
    alpha = textures.arrays[desc["alpha_texture"]][..., 3]
    assert (alpha[:, :2] == 0).all() and (alpha[:, 2:] == 1).all()
    assert desc["alpha_cutoff"] == 0.5
    # A height ramp along u becomes normals tilted towards -u (downhill), uniformly inside.
    normal = textures.arrays[desc["normal_texture"]][2:6, 2:6, :3] * 2 - 1
    assert (normal[..., 0] < -0.1).all() and np.allclose(normal[..., 1], 0, atol=1e-6)
    # The UVs reach the core (OBJ's v flipped).
    np.testing.assert_allclose(entry[5], [[0, 1], [1, 1], [1, 0]])
